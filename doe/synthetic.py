"""A calibration problem with a known answer: closed-form responses inside the fitted model family.

Main effects + two-factor interactions, stiffness on a log scale, with per-response noise levels; the
benchmark (bench/doe.py) and the optimiser tests use the same one so the timing is of a problem whose
answer is checked.
"""
from __future__ import annotations

import math

from .factors import Factor

FACTORS = [Factor("particle_density_kg_m3", 2000, 3000, "kg/m3"), Factor("friction_pp", 0.2, 0.8),
           Factor("friction_pw", 0.1, 0.5), Factor("stiffness_n_m", 1e6, 1e7, "N/m", log=True)]
NOISE = {"bulk_density_kg_m3": 5.0, "friction_angle_deg": 0.3, "confined_modulus_mpa": 0.05,
         "wall_friction_angle_deg": 0.3}
RESPONSES = {
    "bulk_density_kg_m3": lambda p: 0.6 * p["particle_density_kg_m3"] * (1 - 0.05 * p["friction_pp"]),
    "friction_angle_deg": lambda p: 20 + 25 * p["friction_pp"] + 8 * p["friction_pw"]
    + 10 * p["friction_pp"] * p["friction_pw"],
    "confined_modulus_mpa": lambda p: 2 + 3 * math.log10(p["stiffness_n_m"] / 1e6) + 2 * p["friction_pp"],
    "wall_friction_angle_deg": lambda p: 5 + 40 * p["friction_pw"],
}
