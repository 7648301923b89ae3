"""The one key that joins measurements and simulated responses: (test, quantity, condition).

Why one place: a response is matched to its measurement by test, quantity and test condition
(``{"normal_stress_pa": 24000.0}``), and two slightly different matching rules (one exact, one with
a tolerance) silently drop targets. Conditions compare with one relative tolerance, ``REL_TOL``,
loose enough for a value that went through a unit conversion (24 kPa -> 24000.000000000004 Pa) and
tight enough that two real test conditions never meet.

A key also has a plain identifier (``dst__residual_shear_stress_pa__normal_stress_pa_24000``) so that
statistical code can use it as a column name; the key travels with it.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Any, Iterable, Mapping

REL_TOL = 1e-6
ABS_TOL = 1e-12

ConditionItems = tuple[tuple[str, float], ...]


def condition_items(condition: Mapping[str, float] | None) -> ConditionItems:
    return tuple(sorted((str(k), float(v)) for k, v in (condition or {}).items()))


def conditions_equal(a: Mapping[str, float] | None, b: Mapping[str, float] | None) -> bool:
    a, b = dict(a or {}), dict(b or {})
    if set(a) != set(b):
        return False
    return all(math.isclose(float(a[k]), float(b[k]), rel_tol=REL_TOL, abs_tol=ABS_TOL) for k in a)


@dataclass(frozen=True)
class ResponseKey:
    """(test, quantity, condition) of one bulk value; hashable, with a column-safe ``name``."""

    test: str
    quantity: str
    condition: ConditionItems = ()

    @classmethod
    def of(cls, test: str, quantity: str, condition: Mapping[str, float] | None = None) -> "ResponseKey":
        return cls(str(test), str(quantity), condition_items(condition))

    @classmethod
    def from_record(cls, record: Any) -> "ResponseKey":
        """From anything with test/quantity/condition attributes or keys (ORM rows, dicts, BulkProperty)."""
        get = record.get if isinstance(record, Mapping) else lambda k, d=None: getattr(record, k, d)
        return cls.of(get("test"), get("quantity"), get("condition") or {})

    @property
    def condition_dict(self) -> dict[str, float]:
        return dict(self.condition)

    @property
    def name(self) -> str:
        parts = [self.test, self.quantity] + [f"{k}_{v:.6g}" for k, v in self.condition]
        return re.sub(r"[^A-Za-z0-9_]", "_", "__".join(parts))

    @property
    def label(self) -> str:
        """For people: 'dst residual_shear_stress_pa @ normal_stress_pa=24000'."""
        cond = ", ".join(f"{k}={v:g}" for k, v in self.condition)
        return f"{self.test} {self.quantity}" + (f" @ {cond}" if cond else "")

    def matches(self, other: "ResponseKey") -> bool:
        return (self.test == other.test and self.quantity == other.quantity
                and conditions_equal(self.condition_dict, other.condition_dict))

    def stress_pa(self) -> float | None:
        """The normal stress this value was measured at, if its condition has one."""
        return self.condition_dict.get("normal_stress_pa")


def find(keys: Iterable[ResponseKey], wanted: ResponseKey) -> ResponseKey | None:
    """The key among ``keys`` that matches ``wanted`` (same test and quantity, equal condition)."""
    for key in keys:
        if key.matches(wanted):
            return key
    return None


def responses_of(result: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """A LabResult's JSON -> {key name: {test, quantity, condition, unit, value}} (how runs store them)."""
    out = {}
    for prop in result.get("properties", []):
        key = ResponseKey.from_record(prop)
        out[key.name] = {"test": key.test, "quantity": key.quantity, "condition": key.condition_dict,
                         "unit": prop.get("unit", ""), "value": float(prop["value"])}
    return out


def find_response(responses: Mapping[str, Mapping[str, Any]], key: ResponseKey) -> str | None:
    """Name of the stored response (``responses_of`` shape) that matches ``key``."""
    for name, resp in responses.items():
        if key.matches(ResponseKey.from_record(resp)):
            return name
    return None


def select(records: Iterable[Any], wanted: Iterable[Any] | None) -> list[Any]:
    """The records whose key matches one of ``wanted`` (all records if ``wanted`` is None), in wanted order."""
    records = list(records)
    if wanted is None:
        return records
    chosen = []
    for want in wanted:
        key = ResponseKey.from_record(want)
        chosen += [r for r in records if ResponseKey.from_record(r).matches(key) and r not in chosen]
    return chosen
