"""Pluggable contact effects (LIGGGHTS sub-model style), one module each.

An effect module defines ``EFFECT = Effect(...)``: its pydantic parameter model, how it fills its
columns of the per-pair property table, how many history slots it keeps per contact, the stage of the
contact law it hooks into and the name of its numba function. ``engine.kernelgen`` writes a pair kernel
that calls only the active effects, so an unused effect costs nothing. Adding a fifth effect means
adding one module and one line in ``_MODULES`` below.
Modules that are not effects (``rolling_spring``) hold kernel code shared by several effects.
"""
from __future__ import annotations

import importlib

from .base import STAGES, Effect

_MODULES = (
    "engine.effects.hertz_mindlin",
    "engine.effects.cohesion_sjkr",
    "engine.effects.cohesion_adhesive",
    "engine.effects.rolling_epsd",
    "engine.effects.rolling_epsd2",
    "engine.effects.rolling_constant_torque",
)

REGISTRY: dict[str, Effect] = {}


def register(effect: Effect) -> None:
    if effect.stage not in STAGES:
        raise ValueError(f"effect {effect.name}: unknown stage {effect.stage!r}, expected one of {STAGES}")
    REGISTRY[effect.name] = effect


for _m in _MODULES:
    register(importlib.import_module(_m).EFFECT)


def get(name: str) -> Effect:
    try:
        return REGISTRY[name]
    except KeyError:
        raise ValueError(f"unknown contact effect {name!r}; known: {sorted(REGISTRY)}") from None
