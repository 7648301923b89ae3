"""Elastic-plastic spring-dashpot rolling resistance, EPSD (Ai et al. 2011, type C; LIGGGHTS
`rolling_friction epsd`).

The rolling spring has stiffness k_r = 2.25 k_n mu_r^2 R*^2 and is capped at mu_r R* fn, as in
``rolling_epsd2`` but about 20 times softer at mu_r 0.15. A viscous dashpot C_r = eta_r 2 sqrt(I_r k_r)
damps the relative rolling while the spring is below its cap and is off at full mobilisation
(Ai et al.'s eq. 17). I_r is the contact's rolling inertia, 1/I_r = sum over both bodies of
1/(I + m r^2) = 1/(7/5 m r^2) for solid spheres (a wall counts as infinitely heavy).
"""
from __future__ import annotations

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from .base import Effect
from .rolling_spring import rolling_velocity, spring_torque


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # no false for a number: engine.lab.spec.STRICT_INPUT
    rolling_friction: float = Field(ge=0, description="mu_r, dimensionless")
    rolling_damping_ratio: float = Field(0.3, ge=0, le=1, description="eta_r, dimensionless (Ai et al.: 0.3)")


def pair_props(params: Params, contact_type: str, mat_i, mat_other) -> list[float]:
    return [params.rolling_friction, params.rolling_damping_ratio]


@njit(cache=True, inline='always')
def apply(p, hist, h0, n0, n1, n2, w0, w1, w2, fn, r_eff, kn, ks, i_roll, dt):
    mu_r = p[1]
    kr = 2.25 * kn * mu_r * mu_r * r_eff * r_eff
    m0, m1, m2, elastic = spring_torque(hist, h0, n0, n1, n2, w0, w1, w2, kr, mu_r * r_eff * max(fn, 0.0), dt)
    if elastic and kr > 0.0:
        c = 2.0 * p[2] * (i_roll * kr) ** 0.5
        r0, r1, r2 = rolling_velocity(n0, n1, n2, w0, w1, w2)
        m0 -= c * r0
        m1 -= c * r1
        m2 -= c * r2
    return m0, m1, m2


EFFECT = Effect(
    name="rolling_epsd", stage="rolling", params_model=Params, n_props=2, n_hist=3,
    pair_props=pair_props, module=__name__, doc=__doc__,
    standin=lambda p: {"rolling_friction": float(p.rolling_friction)},
)
