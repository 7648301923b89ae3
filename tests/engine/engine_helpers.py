"""Shared helpers for engine tests: small simulations of spheres without the particles package."""
from __future__ import annotations

import math

import numpy as np

from engine.config import MaterialSpec, SimulationConfig


def sphere_mass(radius_m: float, density_kg_m3: float) -> float:
    return density_kg_m3 * 4.0 / 3.0 * math.pi * radius_m ** 3


def config(**kw) -> SimulationConfig:
    mat = {k[4:]: kw.pop(k) for k in list(kw) if k.startswith("mat_")}
    return SimulationConfig(materials=[MaterialSpec(**mat)], **kw)


