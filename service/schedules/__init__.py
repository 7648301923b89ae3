"""Cron schedules that start calibration campaigns; see ``scheduler`` for the missed-run policy."""
