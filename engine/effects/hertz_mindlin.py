"""Hertz-Mindlin (no-slip) normal and tangential stiffness from Young's modulus and Poisson ratio.

fn = 4/3 E* sqrt(R* delta) delta, tangent normal stiffness 2 E* sqrt(R* delta) (used by the dashpot),
ks = 8 G* sqrt(R* delta); the tangential spring stays incremental, as in LIGGGHTS' `hertz` model.
For a particle-wall pair the wall's own modulus is used (default: same as the particle).
"""
from __future__ import annotations

import math

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from .base import Effect


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid")
    young_modulus_pa: float = Field(gt=0)
    poisson_ratio: float = Field(0.25, gt=-1, lt=0.5)
    wall_young_modulus_pa: float | None = Field(None, gt=0)
    wall_poisson_ratio: float | None = Field(None, gt=-1, lt=0.5)


def _shear_modulus(e: float, nu: float) -> float:
    return e / (2.0 * (1.0 + nu))


def pair_props(params: Params, contact_type: str, mat_i, mat_other) -> list[float]:
    e1, nu1 = params.young_modulus_pa, params.poisson_ratio
    if contact_type == "particle-wall":
        e2 = params.wall_young_modulus_pa or e1
        nu2 = params.wall_poisson_ratio if params.wall_poisson_ratio is not None else nu1
    else:
        e2, nu2 = e1, nu1
    e_star = 1.0 / ((1 - nu1**2) / e1 + (1 - nu2**2) / e2)
    g_star = 1.0 / ((2 - nu1) / _shear_modulus(e1, nu1) + (2 - nu2) / _shear_modulus(e2, nu2))
    return [e_star, g_star]


def timestep_limit(params: Params, density_kg_m3: float, r_min_m: float) -> float:
    """Rayleigh time step, the usual critical step for Hertzian contacts."""
    nu = params.poisson_ratio
    g = _shear_modulus(params.young_modulus_pa, nu)
    return math.pi * r_min_m * math.sqrt(density_kg_m3 / g) / (0.1631 * nu + 0.8766)


@njit(cache=True, inline='always')
def apply(p, delta, r_eff, kn, ks):
    root = math.sqrt(r_eff * delta)
    e_star = p[1]
    return 4.0 / 3.0 * e_star * root * delta, 2.0 * e_star * root, 8.0 * p[2] * root


EFFECT = Effect(
    name="hertz_mindlin", stage="stiffness", params_model=Params, n_props=2, n_hist=0,
    pair_props=pair_props, module=__name__, doc=__doc__, timestep_limit=timestep_limit,
)
