"""Simplified JKR cohesion (LIGGGHTS `cohesion sjkr`): an attractive normal force k_c * A.

A = pi a^2 is the area of the circle where the two sphere surfaces intersect (for a wall: the cap
of the sphere cut by the wall), k_c the cohesion energy density in J/m3. Acts while overlapping.
"""
from __future__ import annotations

import math

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from .base import Candidate, Effect


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid")
    cohesion_energy_density_j_m3: float = Field(ge=0)


def pair_props(params: Params, contact_type: str, mat_i, mat_other) -> list[float]:
    return [params.cohesion_energy_density_j_m3]


@njit(cache=True)
def contact_area(delta, r_i, r_j, dist):
    """Area of the intersection circle of two spheres (r_j < 0: sphere and plane)."""
    if r_j < 0.0:
        a2 = r_i * r_i - dist * dist
    else:
        s = dist * dist - r_j * r_j + r_i * r_i
        a2 = (4.0 * dist * dist * r_i * r_i - s * s) / (4.0 * dist * dist)
    if a2 < 0.0:
        a2 = 0.0
    return math.pi * a2


@njit(cache=True, inline='always')
def apply(p, delta, r_i, r_j, dist):
    return -p[1] * contact_area(delta, r_i, r_j, dist)


# Plausible range: a moist aggregate with fines has a bulk cohesion of 1-10 kPa. With a linear contact
# of ~1e6 N/m on 20-40 mm grains, a contact at 30 kPa overlaps ~4e-5 m, so its contact area
# pi R* delta is ~1.5e-6 m2 and a pull of c d^2 ~ 6 N per contact needs k_c ~ 4e6 J/m3: 1e6-1e7 J/m3.
CANDIDATE = Candidate(
    name="cohesion_sjkr", title="cohesion", factor="effects.cohesion_sjkr.cohesion_energy_density_j_m3",
    unit="J/m3", plausible_range=(1.0e6, 1.0e7), step=3.0e6,
    fingerprint={"bulk_density": "-", "cohesion": "++", "angle_of_repose": "++", "pull_force": "+"},
    physics="Moisture and fines bind grains: the Mohr-Coulomb line gains an intercept c > 0 while its "
            "slope stays, the angle of repose rises steeply. Calibration raises phi to compensate, so "
            "the shear-stress residual falls with normal stress (+ at the lowest load, - at the highest).",
)

EFFECT = Effect(
    name="cohesion_sjkr", stage="normal_extra", params_model=Params, n_props=1, n_hist=0,
    pair_props=pair_props, module=__name__, doc=__doc__, candidate=CANDIDATE,
)
