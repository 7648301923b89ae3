"""The physical effects the missing-physics diagnosis can propose, by name: one registry.

Each candidate is declared by the module that implements it: contact effects in
``engine/effects/`` (their ``Effect.candidate``) and particle shape in ``engine/lab/shape.py``.
``calibration/`` and the service read the list from here and nowhere else.
"""
from __future__ import annotations

from engine.effects import REGISTRY
from engine.effects.base import Candidate
from engine.lab.shape import CANDIDATE as _SHAPE


def candidates() -> dict[str, Candidate]:
    """Every diagnosis candidate by name, contact effects in registry order, then shape."""
    out = {name: effect.candidate for name, effect in REGISTRY.items() if effect.candidate is not None}
    out[_SHAPE.name] = _SHAPE
    return out


def get(name: str) -> Candidate:
    table = candidates()
    try:
        return table[name]
    except KeyError:
        raise ValueError(f"unknown effect {name!r}; candidates: {sorted(table)}") from None
