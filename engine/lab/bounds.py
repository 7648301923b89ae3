"""Physical bounds of measured quantities, test conditions and micro parameters: one set of ceilings.

Why: a porosity of 1.7 or a 400 deg friction angle is not a measurement a calibration can match;
accepted, it turns into "targets out of reach", the verdict that should mean missing physics. The
bounds are definitions (a porosity is a volume fraction, an angle of a slope lies between flat and
vertical, an R^2 lies in [0, 1]) or ceilings from the densest and stiffest solids known, so a value
outside them is a typo or a unit mistake, never an unusual material. The API refuses such a value
with a 422 naming the field; the JSON schema shows the same numbers. Each quantity's bound is declared with
the quantity, by its test (``engine.lab.registry``), from the intervals and ceilings here.

Beside each bound, where the literature gives one, a quantity declares its ``Typical`` range: what granular
materials measure (sources in docs/lab.md, "Plausible ranges"). A value outside it is possible, so it is
stored, but is far likelier a unit slip (8,690 Pa for a modulus of 8.69 MPa); ``engine.lab.plausibility``
words the warning, naming the unit that would put the number back in the range.
"""
from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

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
# The largest integer SQLite (and PostgreSQL BIGINT) stores: offsets, counts.
SQLITE_INT_MAX = 2**63 - 1
# The largest id: ids are INTEGER columns, 32-bit on PostgreSQL (SQLite's hold 64 bits); a larger one reached
# the driver there and answered 500 ("integer out of range").
ID_MAX = 2**31 - 1
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


@dataclass(frozen=True)
class Reading:
    """Another meaning the typed number may have had besides a unit of the same quantity, e.g. a friction
    coefficient typed where a friction angle is asked: ``to_si`` turns the typed number into the SI value it
    would then stand for."""

    meaning: str
    to_si: Callable[[float], float]


@dataclass(frozen=True)
class Typical:
    """Where measurements of granular materials usually lie (closed, SI), and whose: ``what`` names the
    population in a sentence ("the confined moduli of granular packings"), ``source`` the short reference
    (the full one is in docs/lab.md). Why not a bound: a value outside is unusual, not impossible."""

    low: float
    high: float
    what: str
    source: str
    readings: tuple[Reading, ...] = ()

    def contains(self, value: float) -> bool:
        return self.low <= value <= self.high


def _degrees_of_coefficient(mu: float) -> float:
    return math.degrees(math.atan(mu))


def _coefficient_of_degrees(angle_deg: float) -> float:
    return math.tan(math.radians(angle_deg)) if abs(angle_deg) < 90 else math.inf


# a friction coefficient typed where an angle is asked (0.9 for 42 deg), and the reverse (31 for 0.6)
AS_FRICTION_COEFFICIENT = Reading("a friction coefficient, the tangent of the angle", _degrees_of_coefficient)
AS_FRICTION_ANGLE_DEG = Reading("a friction angle in degrees", _coefficient_of_degrees)

# Normal stresses of laboratory shear and compression tests on bulk solids: Jenike-type shear cells for powders
# work at a few kPa (ASTM D6128), direct shear of soils at tens to hundreds of kPa (ASTM D3080); the thesis's
# DST ran at 10.5-52.4 kPa and its CCT to 65.6 kPa. 0.5 kPa-2 MPa leaves room on both sides; docs/lab.md,
# "Plausible ranges".
NORMAL_STRESS_TYPICAL = Typical(500.0, 2.0e6, "the normal stresses of laboratory shear and compression tests",
                                "ASTM D6128; ASTM D3080")

# Shared by the quantity declarations (engine/lab/labtests/) and the condition table below.
POSITIVE = Bound(0.0, math.inf, why="positive and finite")
NON_NEGATIVE = Bound(0.0, math.inf, low_open=False, why="non-negative and finite")
SLOPE_ANGLE = Bound(0.0, 90.0, why="an angle between flat and vertical, degrees")
STRESS = Bound(0.0, STIFFEST_SOLID_PA, low_open=False, why="a stress in a granular test, below diamond's modulus")

# Test conditions by the SI-unit suffix of their name (normal_stress_pa, pull_speed_m_s, ...).
CONDITION_BOUNDS: dict[str, Bound] = {
    "Pa": STRESS,
    "m": Bound(0.0, 100.0, why="a laboratory length, metres"),
    "m/s": Bound(0.0, 100.0, why="a laboratory speed, m/s"),
    "N": NON_NEGATIVE,
    "kg": NON_NEGATIVE,
    "deg": Bound(-360.0, 360.0, low_open=False, high_open=False, why="an angle, degrees"),
    "1": NON_NEGATIVE,
}


# Typical micro parameters (attached to their fields in engine.lab.spec.MicroParameters). Solid densities:
# polyethylene 920-960 kg/m3, quartz 2,650, hematite 5,260, steel 7,850 (CRC Handbook of Chemistry and Physics).
PARTICLE_DENSITY_TYPICAL = Typical(800.0, 8000.0, "the solid densities of grains", "CRC Handbook")
# A linear contact stiffness is about E * 2R: grain moduli 1-100 GPa and radii 0.5 mm-5 cm give 1e6-1e10 N/m,
# and DEM practice softens it by up to about 100x to lengthen the time step (Lommen et al. 2014); the thesis's
# k_p 1.72e6 and k_w 1e7 N/m lie inside.
CONTACT_STIFFNESS_TYPICAL = Typical(1.0e4, 1.0e10, "the contact stiffnesses of DEM models of granular materials",
                                    "k = E * 2R; Lommen et al. 2014")
# Measured inter-particle and particle-wall friction coefficients: 0.1-1.0 (thesis Table 4.4: tilt tests 0.54-0.86)
FRICTION_COEFFICIENT_TYPICAL = Typical(0.1, 1.0, "measured contact friction coefficients", "thesis Table 4.4",
                                       readings=(AS_FRICTION_ANGLE_DEG,))

# Typical ranges of test conditions by condition name (a condition without one has no usual range: the
# packing height and pull speed of an anchor test are whatever the apparatus sets).
CONDITION_TYPICAL: dict[str, Typical] = {"normal_stress_pa": NORMAL_STRESS_TYPICAL}


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
