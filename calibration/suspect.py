"""Suspect measurements: a measured quantity far outside anything the model reaches, named with the
unit slip that would bring it back.

Why: a confined modulus typed 1,000 times too small is "out of reach", and a loop that reads every
misfit as missing physics then adds rolling resistance, widens its range, and watches chi2/dof rise
(104.6 -> 132.2 -> 166.3 in issue 33) without ever naming the measurement. A missing effect moves a
bulk response by tens of percent, at most a few times; no candidate at any plausible strength moves
it by an order of magnitude. So a measurement is suspect when

* its value lies more than ``SUSPECT_FACTOR`` (10) times beyond the range of every battery the
  iteration ran (design, confirmation, polishing: the design box's reach of that response), and,
  once the diagnosis has run, beyond every candidate effect's battery extrapolated linearly to
  ``PLAUSIBLE_SLACK`` times the top of its plausible range (the diagnosis's own notion of plausible);
* the far-off values are of one measured quantity (one test and quantity, any of its conditions)
  while some other measured quantity is within reach: when everything is far off, the set-up or the
  model is wrong, not one number.

The likely slip is the power of a thousand (1e3, 1e6, 1e9: kPa for MPa, g/cm3 for kg/m3, kN for N)
that brings every far-off value within ``SLIP_FIT`` (3) times of the model's reach, the nearest to its
middle; with the unit the value was typed in, the unit probably meant is named (typed in kPa, meant
in MPa). Pure functions of what the iteration stored.
"""
from __future__ import annotations

import math
from typing import Any, Iterable, Mapping

from engine.lab.plausibility import _number
from engine.lab.units import UnitError, unit_factors

SUSPECT_FACTOR = 10.0
SLIP_FIT = 3.0
SLIP_FACTORS = (1e3, 1e6, 1e9)


def reach(batteries: Iterable[Mapping[str, Mapping[str, Any]]]) -> dict[str, tuple[float, float]]:
    """Per response name: (smallest, largest) value over ``batteries`` (each a run's stored responses)."""
    out: dict[str, tuple[float, float]] = {}
    for responses in batteries:
        for name, record in (responses or {}).items():
            value = record.get("value") if isinstance(record, Mapping) else None
            if value is None or not math.isfinite(value):
                continue
            lo, hi = out.get(name, (value, value))
            out[name] = (min(lo, value), max(hi, value))
    return out


def extrapolated_candidates(planned: list[tuple[str, Mapping[str, Mapping[str, Any]]]], baseline: str) -> list[dict]:
    """Pseudo-batteries of each candidate at the top of what the diagnosis calls plausible.

    ``planned``: (candidate name, stored responses) of the diagnosis batteries, the baseline's under
    ``baseline``. A strength-type candidate ran at its secant step; its change over the baseline (means
    over the seeds) is scaled linearly to PLAUSIBLE_SLACK x its plausible top. A switch-type candidate
    ran at its matched strength: its batteries are taken as they are."""
    from calibration.attribute import PLAUSIBLE_SLACK
    from engine.candidates import candidates

    table = candidates()

    def means(name: str) -> dict[str, float]:
        sums: dict[str, list[float]] = {}
        for n, responses in planned:
            if n == name:
                for response, record in (responses or {}).items():
                    value = record.get("value")
                    if value is not None and math.isfinite(value):
                        sums.setdefault(response, []).append(float(value))
        return {k: sum(v) / len(v) for k, v in sums.items()}

    base = means(baseline)
    out = []
    for name in dict.fromkeys(n for n, _ in planned if n != baseline):
        c = table.get(name)
        on = means(name)
        if c is None or c.is_switch:
            out.append({k: {"value": v} for k, v in on.items()})
            continue
        off = c.off_value or 0.0
        scale = (PLAUSIBLE_SLACK * (c.plausible_range[1] - off)) / c.step
        out.append({k: {"value": base[k] + (v - base[k]) * scale} for k, v in on.items() if k in base})
    return out


def _slip(values: list[float], lo: float, hi: float, too_small: bool) -> float | None:
    """The factor of the slip that brings every value within SLIP_FIT of [lo, hi], nearest its middle."""
    centre = math.sqrt(lo * hi)
    best = None
    for f in SLIP_FACTORS:
        corrected = [v * f if too_small else v / f for v in values]
        if all(lo / SLIP_FIT <= c <= hi * SLIP_FIT for c in corrected):
            distance = max(abs(math.log(c / centre)) for c in corrected)
            if best is None or distance < best[0]:
                best = (distance, f)
    return None if best is None else best[1]


def _units_of_slip(factor: float, too_small: bool, unit: str, input_unit: str) -> tuple[str | None, str]:
    """(the unit probably meant, how to say it): from the unit typed when it is known (8.69 typed in kPa,
    1,000 times too small: meant MPa), else the unit pairs ``factor`` apart (kPa for MPa, Pa for kPa)."""
    try:
        factors = unit_factors(unit)
    except UnitError:
        return None, ""
    by_factor = {f: u for u, f in factors.items()}
    typed = factors.get(input_unit) if input_unit else None
    if typed is not None:
        meant = by_factor.get(typed * factor if too_small else typed / factor)
        if meant is not None and meant != input_unit:
            return meant, f": typed in {input_unit}, meant in {meant}?"
    pairs = [(a, b) for a, fa in factors.items() for b, fb in factors.items() if math.isclose(fb / fa, factor)]
    if not pairs:
        return None, ""
    said = ", or ".join(f"{small} for {big}" if too_small else f"{big} for {small}" for small, big in pairs)
    return None, f": {said}?"


def suspects(rows: list[dict], reach_by_response: Mapping[str, tuple[float, float]]) -> list[dict]:
    """The suspect measurements among the report's target ``rows`` (modelled ones with a ``response``),
    against the model's reach per response. Empty unless the far-off rows are of one quantity and
    some other quantity is within reach."""
    far: dict[tuple[str, str], list[tuple[dict, float, float, bool]]] = {}
    near: set[tuple[str, str]] = set()
    for row in rows:
        name, measured = row.get("response"), row.get("measured")
        if row.get("status") != "modelled" or name not in reach_by_response or measured is None:
            continue
        lo, hi = reach_by_response[name]
        family = (row["test"], row["quantity"])
        if measured > 0 and lo > 0 and (measured < lo / SUSPECT_FACTOR or measured > hi * SUSPECT_FACTOR):
            far.setdefault(family, []).append((row, lo, hi, measured < lo))
        else:
            near.add(family)
    if len(far) != 1 or not (near - set(far)):
        return []
    (test, quantity), members = next(iter(far.items()))
    directions = {small for _, _, _, small in members}
    if len(directions) != 1:
        return []
    too_small = directions.pop()
    lo, hi = min(m[1] for m in members), max(m[2] for m in members)
    values = [m[0]["measured"] for m in members]
    unit = members[0][0].get("unit") or ""
    ratio = (lo / max(values)) if too_small else (min(values) / hi)
    factor = _slip(values, lo, hi, too_small)
    meant, units = _units_of_slip(factor, too_small, unit, members[0][0].get("input_unit") or "") \
        if factor is not None else (None, "")
    where = _conditions_text([m[0].get("condition") or {} for m in members])
    text = (f"{test} {quantity}{where}: measured {', '.join(_number(v, 4) for v in values)} {unit}, "
            f"{_number(ratio, 3)} times {'below' if too_small else 'above'} anything the model reaches "
            f"({_number(lo, 4)} to {_number(hi, 4)} {unit})")
    if factor is not None:
        text += f"; it looks {factor:,.0f} times too {'small' if too_small else 'large'}{units}"
    else:
        text += "; check the value, its unit and its condition"
    return [{"test": test, "quantity": quantity, "unit": unit,
             "conditions": [m[0].get("condition") or {} for m in members], "measured": values,
             "responses": [m[0]["response"] for m in members], "reach": [lo, hi], "ratio": ratio,
             "direction": "too small" if too_small else "too large", "factor": factor, "meant_unit": meant,
             "message": text}]


def _conditions_text(conditions: list[Mapping[str, float]]) -> str:
    """" at normal_stress_pa 15,000, 30,000" for conditions of one key; "" for none."""
    keys = list(dict.fromkeys(k for c in conditions for k in c))
    if not keys:
        return ""
    return " at " + "; ".join(f"{k} " + ", ".join(_number(float(c[k]), 4) for c in conditions if k in c) for k in keys)
