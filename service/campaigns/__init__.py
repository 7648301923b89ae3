"""Calibration campaigns: configuration, design, runner (state machine), analysis and report."""
