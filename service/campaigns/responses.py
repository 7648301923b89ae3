"""Responses of a battery, keyed like measurements: (test, quantity, condition).

A response gets a plain identifier (``dst__residual_shear_stress_pa__normal_stress_pa_24000``)
so statistical code can use it as a column name; the key it stands for travels with it.
"""
from __future__ import annotations

import math
import re
from typing import Any, Iterable

ConditionKey = tuple[tuple[str, float], ...]
Key = tuple[str, str, ConditionKey]

_REL_TOL = 1e-6


def condition_key(condition: dict[str, float]) -> ConditionKey:
    return tuple(sorted((str(k), float(v)) for k, v in condition.items()))


def response_name(test: str, quantity: str, condition: dict[str, float]) -> str:
    parts = [test, quantity]
    for name, value in condition_key(condition):
        parts.append(f"{name}_{value:.6g}")
    return re.sub(r"[^A-Za-z0-9_]", "_", "__".join(parts))


def conditions_equal(a: dict[str, float], b: dict[str, float]) -> bool:
    if set(a) != set(b):
        return False
    return all(math.isclose(float(a[k]), float(b[k]), rel_tol=_REL_TOL, abs_tol=1e-12) for k in a)


def responses_of(result: dict[str, Any]) -> dict[str, dict[str, Any]]:
    """LabResult JSON -> {response name: {test, quantity, condition, unit, value}}."""
    out = {}
    for prop in result.get("properties", []):
        name = response_name(prop["test"], prop["quantity"], prop.get("condition") or {})
        out[name] = {"test": prop["test"], "quantity": prop["quantity"], "condition": dict(prop.get("condition") or {}),
                     "unit": prop.get("unit", ""), "value": float(prop["value"])}
    return out


def find_response(responses: dict[str, dict[str, Any]], test: str, quantity: str,
                  condition: dict[str, float]) -> str | None:
    for name, resp in responses.items():
        if resp["test"] == test and resp["quantity"] == quantity and conditions_equal(resp["condition"], condition):
            return name
    return None


def select_targets(measurements: Iterable[Any], wanted: list[dict] | None) -> list[Any]:
    """The measurements a campaign calibrates against (all, or those the user listed)."""
    measurements = list(measurements)
    if wanted is None:
        return measurements
    chosen = []
    for want in wanted:
        for m in measurements:
            if m.test == want["test"] and m.quantity == want["quantity"] and conditions_equal(
                    m.condition, want.get("condition") or {}):
                chosen.append(m)
    return chosen
