"""Unit conversion at the API edge: users send kPa, MPa, deg, %, mm; we store SI.

Each canonical quantity has one SI unit, declared with its test (``engine.lab.registry``);
a condition's SI unit is read from its name's suffix (``normal_stress_pa``). The table lives with the lab,
not the service, because the plausibility check (``engine.lab.plausibility``), which the database-free
calibration loop runs too, names the unit a slipped number was probably meant in.
"""
from __future__ import annotations

import math

# SI unit -> {accepted input unit: factor to SI}
_FACTORS: dict[str, dict[str, float]] = {
    "Pa": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9},
    "N/m": {"N/m": 1.0, "kN/m": 1e3, "MN/m": 1e6},
    "N": {"N": 1.0, "kN": 1e3},
    "kg/m3": {"kg/m3": 1.0, "g/cm3": 1e3, "t/m3": 1e3},
    "kg": {"kg": 1.0, "g": 1e-3, "t": 1e3},
    "m": {"m": 1.0, "cm": 1e-2, "mm": 1e-3},
    "m/s": {"m/s": 1.0, "mm/s": 1e-3},
    "deg": {"deg": 1.0, "rad": 180.0 / math.pi},
    "1": {"1": 1.0, "%": 1e-2},
}
_ALIASES = {"kg/m^3": "kg/m3", "kg/m³": "kg/m3", "°": "deg", "degree": "deg", "degrees": "deg",
            "pct": "%", "percent": "%", "": "1", "-": "1"}

# Condition names end with their SI unit; longest suffix first.
_CONDITION_SUFFIXES = (("_m_s", "m/s"), ("_pa", "Pa"), ("_deg", "deg"), ("_kg", "kg"), ("_m", "m"),
                       ("_n", "N"))


class UnitError(ValueError):
    pass


def accepted_units(si_unit: str) -> list[str]:
    return list(unit_factors(si_unit))


def unit_factors(si_unit: str) -> dict[str, float]:
    """Every accepted input unit of ``si_unit`` with its factor to SI."""
    return dict(_FACTORS.get(si_unit, {si_unit: 1.0}))


def canonical_unit(unit: str) -> str:
    """The table's spelling of an accepted unit (kg/m^3 -> kg/m3)."""
    return _ALIASES.get(unit, unit)


def to_si(value: float, unit: str, si_unit: str) -> float:
    """Convert ``value`` given in ``unit`` to ``si_unit``; UnitError if they do not fit."""
    unit = canonical_unit(unit)
    table = unit_factors(si_unit)
    if unit not in table:
        raise UnitError(f"unit {unit!r} cannot express {si_unit!r}; use one of {sorted(table)}")
    return float(value) * table[unit]


# Micro parameters (engine.lab.spec.MicroParameters, engine/effects/ parameters) also end with their SI
# unit, except dimensionless ones (friction and damping coefficients, ratios); longest suffix first.
_PARAMETER_SUFFIXES = (("_n_per_m", "N/m"), ("_kg_m3", "kg/m3"), ("_j_m2", "J/m2"), ("_j_m3", "J/m3"),
                       ("_m_s", "m/s"), ("_pa", "Pa"), ("_deg", "deg"), ("_kg", "kg"), ("_s", "s"), ("_m", "m"))


def parameter_si_unit(name: str) -> str:
    """The SI unit of a micro or effect parameter, read from its name's suffix ("1": dimensionless).

    Why by name: every dimensional parameter is named with its unit (``particle_stiffness_n_per_m``,
    ``surface_energy_j_m2``), so the name is the one declaration; the exported material card
    (service.export.card) states each value with this unit."""
    for suffix, unit in _PARAMETER_SUFFIXES:
        if name.endswith(suffix):
            return unit
    return "1"


# Dimensionless condition names the lab emits (angle-of-repose sector 1..8).
_UNITLESS_CONDITIONS = ("sector",)


def condition_si_unit(name: str) -> str:
    if name in _UNITLESS_CONDITIONS:
        return "1"
    for suffix, unit in _CONDITION_SUFFIXES:
        if name.endswith(suffix):
            return unit
    raise UnitError(f"condition {name!r} must end with its SI unit, e.g. normal_stress_pa, pull_speed_m_s")
