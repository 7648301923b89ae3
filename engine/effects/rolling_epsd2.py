"""Elastic-plastic spring rolling resistance, EPSD2 (Iwashita & Oda 1998; Wensrich & Katterfeld 2012;
LIGGGHTS `rolling_friction epsd2`).

A rolling spring of stiffness k_r = k_t R*^2 (the contact's tangential stiffness times the squared
effective radius) accumulates torque from the relative rolling rotation (twisting about the normal
excluded) and is capped at mu_r R* fn. No rolling dashpot: that is EPSD (``rolling_epsd``), whose
spring is 2.25 k_n mu_r^2 R*^2. At mu_r = 0.15 and k_t = k_n the EPSD2 spring is about 20 times
stiffer than EPSD's, so the two reach full mobilisation at very different rolling angles.
"""
from __future__ import annotations

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from .base import Candidate, Effect
from .rolling_spring import spring_torque


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # no false for a number: engine.lab.spec.STRICT_INPUT
    rolling_friction: float = Field(ge=0, description="mu_r, dimensionless")


def pair_props(params: Params, contact_type: str, mat_i, mat_other) -> list[float]:
    return [params.rolling_friction]


@njit(cache=True, inline='always')
def apply(p, hist, h0, n0, n1, n2, w0, w1, w2, fn, r_eff, kn, ks, i_roll, dt):
    m0, m1, m2, _ = spring_torque(hist, h0, n0, n1, n2, w0, w1, w2, ks * r_eff * r_eff,
                                  p[1] * r_eff * max(fn, 0.0), dt)
    return m0, m1, m2


# Crushed rock: mu_r 0.05-0.5 (Ai et al. 2011; Wensrich & Katterfeld 2012). Rolling resistance stands in
# for the interlocking of angular grains (Estrada et al. 2011), so it aliases with particle shape.
CANDIDATE = Candidate(
    name="rolling_epsd2", title="rolling resistance", factor="effects.rolling_epsd2.rolling_friction",
    unit="1", plausible_range=(0.05, 0.5), step=0.15,
    fingerprint={"bulk_density": "-", "friction_angle": "+", "dilatancy": "+", "angle_of_repose": "+",
                 "pull_force": "+"},
    physics="Angular grains resist rolling: strength (phi), dilatancy, angle of repose and pull-out "
            "force rise and the packing loosens. Round spheres without it saturate near phi 40-45 deg "
            "however high the sliding friction (Estrada et al. 2008), so mu_pp calibrates to its upper "
            "bound and the friction angle stays out of reach.",
    revealed_by=(("dst", "residual_shear_stress_pa", "at each normal load"), ("aor", "angle_of_repose_deg", "")),
)

EFFECT = Effect(
    name="rolling_epsd2", stage="rolling", params_model=Params, n_props=1, n_hist=3,
    pair_props=pair_props, module=__name__, doc=__doc__, candidate=CANDIDATE,
    standin=lambda p: {"rolling_friction": float(p.rolling_friction)},
)
