"""Hertz-Mindlin (no-slip) normal and tangential stiffness from Young's modulus and Poisson ratio.

fn = 4/3 E* sqrt(R* delta) delta, tangent normal stiffness 2 E* sqrt(R* delta) (used by the dashpot),
ks = 8 G* sqrt(R* delta); the tangential spring stays incremental, as in LIGGGHTS' `hertz` model.
For a particle-wall pair the wall's own modulus is used (default: same as the particle).
"""
from __future__ import annotations

import math

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from .base import Candidate, Effect


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # no false for a number: engine.lab.spec.STRICT_INPUT
    young_modulus_pa: float = Field(gt=0, description="E of the particles")
    poisson_ratio: float = Field(0.25, gt=-1, lt=0.5, description="nu of the particles")
    wall_young_modulus_pa: float | None = Field(None, gt=0, description="E of the walls; null: the particles'")
    wall_poisson_ratio: float | None = Field(None, gt=-1, lt=0.5, description="nu of the walls; null: the particles'")


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


# The largest overlap the critical step is judged at, as a fraction of the smaller radius: the usual ceiling on
# overlaps in DEM. Why a limit beyond Rayleigh's: Rayleigh's step is a wave's time across a grain, not the
# stability bound of a stiff damped contact. The tangential mode couples rotation (2/7 of the translational mass
# for spheres), so with LIGGGHTS' tangential dashpot (damping ratio 0.8 on the translational mass) it runs at
# 1.5 of critical damping, and velocity Verlet with the dashpot on the half step is stable only below
# w dt = 2 (sqrt(1 + z^2) - z) = 0.61. At E 4 GPa (tier B hertz_strong's stiff corner) 0.3 x Rayleigh's step
# passed that bound above 1.6 % overlap, which the fill's impacts reach (about 4 % at 9.6 m/s), and the fill
# never came to rest (kinetic energy ratio 8.3e-3 after 6 s); at 0.3 x the bound at 1 % it settled in 1.5 s
# (docs/lab.md). The step is about 3x shorter than 0.3 x Rayleigh's for every E (both scale as E^(-1/2)).
REFERENCE_OVERLAP_FRACTION = 0.01


def contact_stiffness(params: Params, contact_type: str, r_min_m: float) -> tuple[float, float]:
    """(normal tangent, tangential) stiffness of the stiffest such contact at REFERENCE_OVERLAP_FRACTION."""
    e_star, g_star = pair_props(params, contact_type, None, None)
    r_eff = r_min_m if contact_type == "particle-wall" else 0.5 * r_min_m
    root = math.sqrt(r_eff * REFERENCE_OVERLAP_FRACTION * r_min_m)
    return 2.0 * e_star * root, 8.0 * g_star * root


def timestep_limit(params: Params, density_kg_m3: float, r_min_m: float) -> float:
    """Rayleigh time step, the usual critical step for Hertzian contacts (the damped modes: contact_stiffness)."""
    nu = params.poisson_ratio
    g = _shear_modulus(params.young_modulus_pa, nu)
    return math.pi * r_min_m * math.sqrt(density_kg_m3 / g) / (0.1631 * nu + 0.8766)


@njit(cache=True, inline='always')
def apply(p, delta, r_eff, kn, ks):
    root = math.sqrt(r_eff * delta)
    e_star = p[1]
    return 4.0 / 3.0 * e_star * root * delta, 2.0 * e_star * root, 8.0 * p[2] * root


# Stress at which a Hertzian contact is matched to the linear one (mid range of the thesis's CCT,
# 10-66 kPa) and the grain radius assumed when the spec does not set one (the screening spheres).
MATCH_STRESS_PA = 30.0e3
_DEFAULT_RADIUS_M = 0.020


def matched_young_modulus_pa(parameters, poisson_ratio: float = 0.25) -> float:
    """Young's modulus whose Hertzian tangent stiffness equals the linear contact's at MATCH_STRESS_PA.

    PFC's linear contact of two grains has kn = kp/2 (springs in series). A grain of diameter d in a
    packing at stress sigma carries about sigma d^2 per contact (one contact per d^2 of a section, the
    usual estimate), so the Hertz overlap is delta = (3 F / (4 E* sqrt(R*)))^(2/3) with R* = d/4, and
    the tangent stiffness 2 E* sqrt(R* delta) equals kn when E* = kn^(3/2) / (sqrt(6 F R*)).
    Switching Hertz-Mindlin on at this modulus changes how E' grows with stress, not its level at
    30 kPa: the diagnosis then sees the shape of the effect alone.
    """
    radius_m = parameters.particle_radius_m or _DEFAULT_RADIUS_M
    diameter_m = 2.0 * radius_m
    kn = 0.5 * parameters.particle_stiffness_n_per_m
    force_n = MATCH_STRESS_PA * diameter_m**2
    r_star = 0.5 * radius_m
    e_star = kn**1.5 / math.sqrt(6.0 * force_n * r_star)
    # E* = E / (2 (1 - nu^2)) for two grains of one material
    return 2.0 * (1.0 - poisson_ratio**2) * e_star


CANDIDATE = Candidate(
    name="hertz_mindlin", title="non-linear (Hertzian) contact stiffness",
    factor="effects.hertz_mindlin.young_modulus_pa", unit="Pa", plausible_range=(1.0e8, 1.0e10),
    step=1.0, off_value=None, reference=matched_young_modulus_pa,
    fingerprint={"modulus_slope": "++"},
    physics="A Hertzian contact stiffens as it is loaded, so the confined modulus grows with stress "
            "(E' ~ sigma^(1/3) in effective-medium theory, ~sigma^(1/2) measured, Makse et al. 2004) "
            "where a linear spring gives a flat E'. With the level fitted through kp the E' residual is "
            "- at the lowest stress and + at the highest; strength, dilatancy and the pile do not change. "
            "In loose packings the loading E' also grows with the contact network under either law, so "
            "the unloading (unload-reload) modulus, read on a fixed network, is where the law shows.",
    # measured on tier B's packings (docs/diagnosis.md, hertz_strong): E' windows from 3 to 60 kPa left the
    # Hertzian world within the linear model's noise; E_ur at the same stresses rejected it (p 0.0032)
    revealed_by=(("cct", "unload_reload_modulus_pa", "at several normal stresses, e.g. 3-60 kPa "
                  "(options.cct_unload_reload_stresses_pa)"),),
    # ``apply`` reads E* and G* only: the linear spring's kp is left to bound the time step (engine.timestep)
    supersedes=("particle_stiffness_n_per_m",),
)

EFFECT = Effect(
    name="hertz_mindlin", stage="stiffness", params_model=Params, n_props=2, n_hist=0,
    pair_props=pair_props, module=__name__, doc=__doc__, timestep_limit=timestep_limit,
    contact_stiffness=contact_stiffness,
    candidate=CANDIDATE,
    standin=lambda p: {"hertz_young_modulus_pa": float(p.young_modulus_pa), "hertz_poisson_ratio": float(p.poisson_ratio)},
)
