"""Adhesive contact with a tensile range: a linear adhesive branch up to a JKR pull-off force.

Each contact carries an attraction that grows with the contact law's elastic force fn_el at twice its
rate until it saturates at twice the pull-off force F_c:

    f_normal = fn_el - 2 min(fn_el, F_c),    F_c = 3/2 pi Gamma R*

so the net elastic force is -fn_el (tension, the adhesive branch) while fn_el < F_c, reaches its most
tensile value -F_c at fn_el = F_c, and is fn_el - 2 F_c beyond. Two grains pressed together and
pulled apart therefore hold up to F_c in tension, whatever their stiffness and whatever load pressed
them together, and let go when the overlap reaches zero. F_c is the Johnson-Kendall-Roberts pull-off
force of two spheres of effective radius R* with a surface energy Gamma (Johnson et al. 1971); for a
coarse aggregate Gamma is an effective binding energy of fines and moisture films, orders of
magnitude above a clean surface's.

This is what gives a bulk material a Mohr-Coulomb intercept (a tensile strength sigma_t ~ (1 - n)/n
F_c / d^2 by Rumpf's estimate). The simplified JKR model (``cohesion_sjkr``) acts only while grains
overlap and grows with the overlap, so on a linear spring it is a softer spring with a raised friction
limit and leaves no intercept. The Coulomb limit stays mu times the repulsive force fn_el, which is
2 F_c at zero net force: Thornton & Yin's (1991) rule mu (fn + 2 F_c) for adhesive contacts.

Wall contacts use R* = the particle radius. The force is conservative (continuous in the overlap):
the contact law's dashpot does all the dissipating.
"""
from __future__ import annotations

import math

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from .base import Candidate, Effect


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # no false for a number: engine.lab.spec.STRICT_INPUT
    # at most 50 x the plausible top: beyond it the attraction outweighs any contact's repulsion at the
    # lab's stresses and the packing collapses into itself
    surface_energy_j_m2: float = Field(ge=0, le=1.0e4, description="Gamma, J/m2: pull-off force 3/2 pi Gamma R*")


def pair_props(params: Params, contact_type: str, mat_i, mat_other) -> list[float]:
    return [1.5 * math.pi * params.surface_energy_j_m2]


@njit(cache=True)
def pull_off_force(force_per_radius, r_i, r_j):
    """F_c = 3/2 pi Gamma R* (r_j < 0: a wall, R* = r_i)."""
    r_eff = r_i if r_j < 0.0 else r_i * r_j / (r_i + r_j)
    return force_per_radius * r_eff


@njit(cache=True, inline='always')
def apply(p, delta, r_i, r_j, dist, fn_elastic):
    f_c = pull_off_force(p[1], r_i, r_j)
    return -2.0 * min(max(fn_elastic, 0.0), f_c)


# Plausible range: a moist or clayey aggregate has a bulk cohesion of 1-10 kPa. By Rumpf's estimate
# sigma_t ~ 1.5 F_c / d^2 for a porosity of 0.4, so at d = 40 mm (the screening spheres, R* = 10 mm)
# 1-10 kPa needs F_c ~ 1-10 N, i.e. Gamma = F_c / (3/2 pi R*) ~ 20-200 J/m2.
CANDIDATE = Candidate(
    name="cohesion_adhesive", title="cohesion", factor="effects.cohesion_adhesive.surface_energy_j_m2",
    unit="J/m2", plausible_range=(20.0, 200.0), step=60.0,
    fingerprint={"bulk_density": "-", "cohesion": "++", "angle_of_repose": "++", "pull_force": "+"},
    physics="Moisture and fines bind grains: the Mohr-Coulomb line gains an intercept c > 0 while its "
            "slope stays, the angle of repose rises steeply. Calibration raises phi to compensate, so "
            "the shear-stress residual falls with normal stress (+ at the lowest load, - at the highest).",
    # the intercept is the largest share of the strength at the lowest loads
    revealed_by=(("dst", "residual_shear_stress_pa", "at low normal loads (the Mohr-Coulomb intercept)"),
                 ("aor", "angle_of_repose_deg", "")),
)

EFFECT = Effect(
    name="cohesion_adhesive", stage="normal_extra", params_model=Params, n_props=1, n_hist=0,
    pair_props=pair_props, module=__name__, doc=__doc__, candidate=CANDIDATE,
    standin=lambda p: {"surface_energy_j_m2": float(p.surface_energy_j_m2)},
)
