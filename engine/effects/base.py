"""The interface every contact effect implements.

Stages (the order the pair kernel runs them in, with the numba function's signature):

* ``"stiffness"``: ``apply(p, delta, r_eff, kn, ks) -> (fn_elastic, kn_tangent, ks)`` replaces the
  linear normal force and the stiffnesses (used for damping and the time step) of the contact.
* ``"normal_extra"``: ``apply(p, delta, r_i, r_j, dist) -> f_normal`` adds a normal force (positive
  pushes apart); ``r_j < 0`` marks a wall.
* ``"rolling"``: ``apply(p, hist, h0, n0, n1, n2, w0, w1, w2, fn, r_eff, kn, dt) -> (t0, t1, t2)``
  returns the torque on particle i (particle j gets the opposite); ``w`` is the relative angular
  velocity omega_i - omega_j, ``hist[h0:h0 + n_hist]`` are this effect's history slots.

History slots must hold quantities of i relative to j that change sign when i and j swap roles: the
engine renumbers particles for locality and stores each pair once with i < j, negating the history
of pairs whose order flips.

``p`` (length ``1 + n_props``) is this effect's slice of the pair-property row; ``p[0]`` is written by the framework (1 where the
effect is on for the pair) and the kernel skips the call where it is 0.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from pydantic import BaseModel

STAGES = ("stiffness", "normal_extra", "rolling")


@dataclass(frozen=True)
class Effect:
    name: str
    stage: str
    params_model: type[BaseModel]
    n_props: int
    n_hist: int
    # (params, contact_type, material_i, material_other) -> n_props floats (p[1:], p[0] is the switch)
    pair_props: Callable[..., list[float]]
    module: str
    function: str = "apply"
    doc: str = ""
    # critical time step this effect imposes: (params, density_kg_m3, r_min_m) -> dt_s (None: none)
    timestep_limit: Callable[..., float] | None = None
