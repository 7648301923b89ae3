"""The background ticker keeps calling its ticks, and a failing tick does not stop the others."""
from __future__ import annotations

import threading

from service.background import BackgroundTicker, default_ticks


def test_ticker_survives_failing_tick():
    calls = {"good": 0, "bad": 0}
    enough = threading.Event()

    def bad():
        calls["bad"] += 1
        raise RuntimeError("campaign step blew up")

    def good():
        calls["good"] += 1
        if calls["good"] >= 3:
            enough.set()

    ticker = BackgroundTicker(0.01, [("bad", bad), ("good", good)])
    ticker.start()
    assert enough.wait(10)
    ticker.stop()
    assert not ticker.is_alive()
    assert calls["bad"] >= 3


def test_default_ticks_are_the_campaign_runner_and_scheduler(session_factory, settings):
    names = [name for name, _ in default_ticks(session_factory, settings)]
    assert names == ["campaigns", "schedules"]
    for _name, tick in default_ticks(session_factory, settings):
        tick()  # idempotent on an empty database
