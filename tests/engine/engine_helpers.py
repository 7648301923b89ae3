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




G = 9.81


def tilted_gravity(angle_deg: float) -> tuple[float, float, float]:
    """Gravity for an incline of angle_deg modelled as a level floor: downslope is +x."""
    a = math.radians(angle_deg)
    return (G * math.sin(a), 0.0, -G * math.cos(a))


def fit_acceleration(times, values) -> float:
    return float(np.polyfit(np.asarray(times), np.asarray(values), 1)[0])
