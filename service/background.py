"""The service's background thread: campaign runner and scheduler ticks, worker supervision.

Each tick reads everything it needs from the database and is idempotent, so a
restarted service simply carries on; a failing tick is logged and retried at
the next interval instead of killing the thread.
"""
from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from datetime import datetime, timezone

from sqlalchemy.orm import Session, sessionmaker

from service.campaigns.runner import CampaignRunner
from service.config import Settings
from service.schedules.scheduler import Scheduler

log = logging.getLogger(__name__)


def default_ticks(session_factory: sessionmaker[Session], settings: Settings) -> list[tuple[str, Callable[[], object]]]:
    """The campaign runner and the scheduler, each called once per tick."""
    runner = CampaignRunner(session_factory, settings)
    scheduler = Scheduler(session_factory, settings)
    return [
        ("campaigns", runner.tick),
        ("schedules", lambda: scheduler.tick(datetime.now(timezone.utc).replace(tzinfo=None))),
    ]


class BackgroundTicker(threading.Thread):
    def __init__(self, interval_s: float, ticks: list[tuple[str, Callable[[], object]]]):
        super().__init__(name="demcal-background", daemon=True)
        self.interval_s, self.ticks = interval_s, ticks
        self.stop_event = threading.Event()

    def tick(self) -> None:
        for name, fn in self.ticks:
            if self.stop_event.is_set():
                return
            try:
                fn()
            except Exception:
                log.exception("background tick %r failed; retrying next interval", name)

    def run(self) -> None:
        while not self.stop_event.wait(self.interval_s):
            self.tick()

    def stop(self, timeout_s: float = 10.0) -> None:
        self.stop_event.set()
        if self.is_alive():
            self.join(timeout_s)
