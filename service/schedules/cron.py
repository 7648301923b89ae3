"""A small 5-field cron parser (minute hour day-of-month month day-of-week), UTC.

Written here rather than taken from croniter: we need ~100 lines of it, the
semantics we promise are exactly these, and each is tested. Supported: ``*``,
numbers, ``a-b`` ranges, ``/step`` on ``*`` or ranges, ``,`` lists, month and
weekday names (``jan``, ``mon``), weekday 7 = Sunday, and the macros
``@hourly @daily @midnight @weekly @monthly @yearly @annually``. As in Vixie
cron, when both day-of-month and day-of-week are restricted a day matches if
*either* does.
"""
from __future__ import annotations

from dataclasses import dataclass
from datetime import datetime, timedelta

MACROS = {"@hourly": "0 * * * *", "@daily": "0 0 * * *", "@midnight": "0 0 * * *",
          "@weekly": "0 0 * * 0", "@monthly": "0 0 1 * *", "@yearly": "0 0 1 1 *", "@annually": "0 0 1 1 *"}
_MONTHS = {n: i for i, n in enumerate(["jan", "feb", "mar", "apr", "may", "jun", "jul", "aug", "sep", "oct",
                                       "nov", "dec"], start=1)}
_DAYS = {n: i for i, n in enumerate(["sun", "mon", "tue", "wed", "thu", "fri", "sat"])}
_FIELDS = (("minute", 0, 59, {}), ("hour", 0, 23, {}), ("day of month", 1, 31, {}), ("month", 1, 12, _MONTHS),
           ("day of week", 0, 7, _DAYS))
_MAX_SEARCH_DAYS = 366 * 8  # long enough to reach the next Feb 29


class CronError(ValueError):
    pass


def _value(text: str, name: str, lo: int, hi: int, names: dict[str, int]) -> int:
    key = text.lower()
    if key in names:
        return names[key]
    if not text.isdigit():
        raise CronError(f"{name}: {text!r} is not a number{' or name' if names else ''}")
    value = int(text)
    if not lo <= value <= hi:
        raise CronError(f"{name}: {value} is outside {lo}-{hi}")
    return value


def _field(text: str, name: str, lo: int, hi: int, names: dict[str, int]) -> frozenset[int]:
    out: set[int] = set()
    for part in text.split(","):
        if not part:
            raise CronError(f"{name}: empty list item in {text!r}")
        base, _, step_text = part.partition("/")
        step = 1
        if _:
            if not step_text.isdigit() or int(step_text) < 1:
                raise CronError(f"{name}: step {step_text!r} must be a positive integer")
            step = int(step_text)
        if base == "*":
            start, end = lo, hi
        elif "-" in base:
            a, b = base.split("-", 1)
            start, end = _value(a, name, lo, hi, names), _value(b, name, lo, hi, names)
            if start > end:
                raise CronError(f"{name}: range {base!r} runs backwards")
        else:
            start = _value(base, name, lo, hi, names)
            end = hi if _ else start  # '5/15' means 5, 20, 35, 50
        out.update(range(start, end + 1, step))
    return frozenset(out)


@dataclass(frozen=True)
class Cron:
    expression: str
    minutes: frozenset[int]
    hours: frozenset[int]
    days: frozenset[int]
    months: frozenset[int]
    weekdays: frozenset[int]  # 0 = Sunday
    dom_restricted: bool
    dow_restricted: bool

    def _day_matches(self, day: datetime) -> bool:
        if day.month not in self.months:
            return False
        dom = day.day in self.days
        dow = (day.isoweekday() % 7) in self.weekdays
        if self.dom_restricted and self.dow_restricted:
            return dom or dow
        return dom and dow

    def next_after(self, when: datetime) -> datetime:
        """First matching minute strictly after ``when`` (naive UTC)."""
        start = when.replace(second=0, microsecond=0) + timedelta(minutes=1)
        day = start.replace(hour=0, minute=0)
        for offset in range(_MAX_SEARCH_DAYS):
            current = day + timedelta(days=offset)
            if not self._day_matches(current):
                continue
            for hour in sorted(self.hours):
                for minute in sorted(self.minutes):
                    candidate = current.replace(hour=hour, minute=minute)
                    if candidate >= start:
                        return candidate
        raise CronError(f"{self.expression!r} never fires")

    def upcoming(self, when: datetime, count: int) -> list[datetime]:
        out = []
        for _ in range(count):
            when = self.next_after(when)
            out.append(when)
        return out


def parse_cron(expression: str) -> Cron:
    text = " ".join(expression.split())
    text = MACROS.get(text.lower(), text)
    parts = text.split(" ")
    if len(parts) != 5:
        raise CronError(f"{expression!r}: expected 5 fields (minute hour day-of-month month day-of-week) "
                        f"or one of {sorted(MACROS)}")
    sets = [_field(p, *spec) for p, spec in zip(parts, _FIELDS)]
    weekdays = frozenset(d % 7 for d in sets[4])
    cron = Cron(expression, sets[0], sets[1], sets[2], sets[3], weekdays,
                dom_restricted=parts[2] != "*", dow_restricted=parts[4] != "*")
    cron.next_after(datetime(2000, 1, 1))  # e.g. '0 0 31 2 *' never fires: refuse it now
    return cron
