"""Elastic-plastic spring rolling resistance, EPSD2 / type C (Ai et al. 2011; LIGGGHTS `epsd2`).

A rolling spring k_r = 2.25 kn mu_r^2 R*^2 accumulates torque from the relative rolling rotation
(normal twisting excluded) and is capped at mu_r R* fn. No rolling dashpot (that is EPSD).
"""
from __future__ import annotations

import math

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from ..springs import onto_plane_keep_length
from .base import Candidate, Effect


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid")
    rolling_friction: float = Field(ge=0, description="mu_r, dimensionless")


def pair_props(params: Params, contact_type: str, mat_i, mat_other) -> list[float]:
    return [params.rolling_friction]


@njit(cache=True, inline='always')
def apply(p, hist, h0, n0, n1, n2, w0, w1, w2, fn, r_eff, kn, dt):
    mu_r = p[1]
    wn = w0 * n0 + w1 * n1 + w2 * n2
    w0 -= wn * n0
    w1 -= wn * n1
    w2 -= wn * n2
    # keep the spring torque in the current tangent plane, magnitude preserved
    m0, m1, m2 = onto_plane_keep_length(hist[h0], hist[h0 + 1], hist[h0 + 2], n0, n1, n2)
    kr = 2.25 * kn * mu_r * mu_r * r_eff * r_eff
    m0 -= kr * w0 * dt
    m1 -= kr * w1 * dt
    m2 -= kr * w2 * dt
    limit = mu_r * r_eff * max(fn, 0.0)
    mag = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    if mag > limit:
        s = limit / mag if mag > 0.0 else 0.0
        m0 *= s
        m1 *= s
        m2 *= s
    hist[h0] = m0
    hist[h0 + 1] = m1
    hist[h0 + 2] = m2
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
)

EFFECT = Effect(
    name="rolling_epsd2", stage="rolling", params_model=Params, n_props=1, n_hist=3,
    pair_props=pair_props, module=__name__, doc=__doc__, candidate=CANDIDATE,
)
