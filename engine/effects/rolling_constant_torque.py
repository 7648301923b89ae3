"""Constant directional torque rolling resistance, type A (Ai et al. 2011; LIGGGHTS `cdt`).

A torque of magnitude mu_r R* fn opposes the relative rolling velocity. Cheap, but it chatters
around rest since it has no elastic part.
"""
from __future__ import annotations

import math

from numba import njit
from pydantic import BaseModel, ConfigDict, Field

from .base import Effect


class Params(BaseModel):
    model_config = ConfigDict(extra="forbid", strict=True)  # no false for a number: engine.lab.spec.STRICT_INPUT
    rolling_friction: float = Field(ge=0, description="mu_r, dimensionless")


def pair_props(params: Params, contact_type: str, mat_i, mat_other) -> list[float]:
    return [params.rolling_friction]


@njit(cache=True, inline='always')
def apply(p, hist, h0, n0, n1, n2, w0, w1, w2, fn, r_eff, kn, ks, i_roll, dt):
    wn = w0 * n0 + w1 * n1 + w2 * n2
    w0 -= wn * n0
    w1 -= wn * n1
    w2 -= wn * n2
    mag = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if mag < 1e-12:
        return 0.0, 0.0, 0.0
    s = -p[1] * r_eff * max(fn, 0.0) / mag
    return s * w0, s * w1, s * w2


EFFECT = Effect(
    name="rolling_constant_torque", stage="rolling", params_model=Params, n_props=1, n_hist=0,
    pair_props=pair_props, module=__name__, doc=__doc__,
    standin=lambda p: {"rolling_friction": float(p.rolling_friction)},
)
