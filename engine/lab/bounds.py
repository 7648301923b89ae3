"""Physical bounds of every measured quantity and of the micro parameters: one table, used everywhere.

Why: a porosity of 1.7 or a 400 deg friction angle is not a measurement a calibration can match;
accepted, it turns into "targets out of reach", the verdict that should mean missing physics. The
bounds are definitions (a porosity is a volume fraction, an angle of a slope lies between flat and
vertical, an R^2 lies in [0, 1]) or ceilings from the densest and stiffest solids known, so a value
outside them is a typo or a unit mistake, never an unusual material. The API refuses such a value
with a 422 naming the field; the JSON schema shows the same numbers.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from engine.lab.result import QUANTITIES

# Osmium, the densest element at room conditions: 22,590 kg/m3. No particle (and no bulk packing of
# particles, which holds voids) is denser.
DENSEST_SOLID_KG_M3 = 22_590.0
# Diamond's Young's modulus, about 1.22e12 Pa, the stiffest bulk solid. A packing's constrained modulus,
# and any stress a granular test applies, stays below it.
STIFFEST_SOLID_PA = 1.22e12
# A PFC-style linear contact stiffness is about E * 2R: diamond with a 0.5 m radius (the largest particle
# the lab accepts) gives ~1.2e12 N/m.
MAX_CONTACT_STIFFNESS_N_PER_M = STIFFEST_SOLID_PA * 2 * 0.5
# Particle radius range of the lab: 10 um (finer powders are cohesive and outside this contact model) to
# 0.5 m (the thesis's whole shear box is 0.59 m across).
MIN_PARTICLE_RADIUS_M = 1e-5
MAX_PARTICLE_RADIUS_M = 0.5
# A Coulomb friction coefficient is tan of a friction angle; 10 is tan(84.3 deg), steeper than any slope a
# contact of real materials holds (measured inter-particle and wall values are 0.1-1.0; thesis Table 4.4).
MAX_FRICTION_COEFFICIENT = 10.0
# The largest integer SQLite (and PostgreSQL BIGINT) stores: ids, offsets, counts.
SQLITE_INT_MAX = 2**63 - 1
# Random seeds are 32-bit (numpy's SeedSequence accepts more, but seeds are stored and replayed).
MAX_SEED = 2**32 - 1


@dataclass(frozen=True)
class Bound:
    """An interval with open or closed ends; ``why`` is shown to the user on refusal."""

    low: float = -math.inf
    high: float = math.inf
    low_open: bool = True
    high_open: bool = True
    why: str = ""

    def contains(self, value: float) -> bool:
        if not math.isfinite(value):
            return False
        above = value > self.low if self.low_open else value >= self.low
        below = value < self.high if self.high_open else value <= self.high
        return above and below

    def describe(self) -> str:
        left = "(" if self.low_open else "["
        right = ")" if self.high_open else "]"
        return f"{left}{self.low:g}, {self.high:g}{right}" + (f" ({self.why})" if self.why else "")

    def check(self, value: float, what: str) -> None:
        """ValueError naming ``what`` when ``value`` is outside (or not finite)."""
        if not self.contains(value):
            raise ValueError(f"{what} = {value:g} is outside {self.describe()}")


_POSITIVE = Bound(0.0, math.inf, why="positive and finite")
_NON_NEGATIVE = Bound(0.0, math.inf, low_open=False, why="non-negative and finite")
_SLOPE_ANGLE = Bound(0.0, 90.0, why="an angle between flat and vertical, degrees")
_STRESS = Bound(0.0, STIFFEST_SOLID_PA, low_open=False, why="a stress in a granular test, below diamond's modulus")

# (test, quantity) -> bounds of a measured (or simulated) value, SI.
QUANTITY_BOUNDS: dict[tuple[str, str], Bound] = {
    ("fill", "bulk_density_kg_m3"): Bound(0.0, DENSEST_SOLID_KG_M3, high_open=False,
                                          why="below the densest solid, osmium"),
    ("fill", "porosity"): Bound(0.0, 1.0, why="a void volume fraction"),
    ("fill", "voids_ratio"): _POSITIVE,  # e = n / (1 - n): any positive number for n in (0, 1)
    ("fill", "packing_height_m"): _POSITIVE,
    ("fill", "bulk_mass_kg"): _POSITIVE,
    ("fill", "particle_count"): Bound(1.0, float(SQLITE_INT_MAX), low_open=False, why="a count of particles"),
    ("cct", "confined_modulus_pa"): Bound(0.0, STIFFEST_SOLID_PA, high_open=False, why="below diamond's modulus"),
    ("cct", "bulk_stiffness_n_per_m"): _POSITIVE,
    ("dst", "residual_shear_stress_pa"): _STRESS,
    # Negative dilatancy is contraction, physical for loose packings: the whole open range about zero.
    ("dst", "dilatancy_angle_deg"): Bound(-90.0, 90.0, why="an angle between -90 and 90 degrees"),
    ("dst", "friction_angle_deg"): _SLOPE_ANGLE,
    # A Mohr-Coulomb intercept; a fit through scattered points may put it slightly below zero.
    ("dst", "cohesion_pa"): Bound(-STIFFEST_SOLID_PA, STIFFEST_SOLID_PA, why="a Mohr-Coulomb intercept"),
    ("dst", "mohr_coulomb_r2"): Bound(0.0, 1.0, low_open=False, high_open=False, why="a coefficient of determination"),
    ("aor", "angle_of_repose_deg"): _SLOPE_ANGLE,
    ("anchor", "peak_pull_force_n"): _POSITIVE,
}
assert set(QUANTITY_BOUNDS) == {(t, q) for t, qs in QUANTITIES.items() for q in qs}, "every quantity has bounds"

# Test conditions by the SI-unit suffix of their name (normal_stress_pa, pull_speed_m_s, ...).
CONDITION_BOUNDS: dict[str, Bound] = {
    "Pa": _STRESS,
    "m": Bound(0.0, 100.0, why="a laboratory length, metres"),
    "m/s": Bound(0.0, 100.0, why="a laboratory speed, m/s"),
    "N": _NON_NEGATIVE,
    "kg": _NON_NEGATIVE,
    "deg": Bound(-360.0, 360.0, low_open=False, high_open=False, why="an angle, degrees"),
    "1": _NON_NEGATIVE,
}


def quantity_bound(test: str, quantity: str) -> Bound:
    return QUANTITY_BOUNDS[(test, quantity)]


def check_finite_tree(value, path: str = "") -> None:
    """ValueError naming the first NaN or infinity anywhere in nested dicts/lists (JSON has neither)."""
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return
    if isinstance(value, float):
        if not math.isfinite(value):
            raise ValueError(f"{path or 'value'} must be a finite number, not {value}")
    elif isinstance(value, dict):
        for key, item in value.items():
            check_finite_tree(item, f"{path}.{key}" if path else str(key))
    elif isinstance(value, (list, tuple)):
        for index, item in enumerate(value):
            check_finite_tree(item, f"{path}[{index}]")
