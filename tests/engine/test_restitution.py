"""Two-sphere and sphere-wall normal impact against the linear spring-dashpot solution.

e = exp(-pi xi / sqrt(1 - xi^2)), contact time t_c = pi / (w sqrt(1 - xi^2)), w = sqrt(kn / m_eff),
with the PFC series stiffness kn = kp / 2 for two equal spheres and kp kw / (kp + kw) against a wall.
"""
import math

import numpy as np
import pytest

from engine.config import PlaneGeom, WallSpec
from engine.simulation import Simulation

from engine_helpers import config, sphere_mass

R = 0.01
RHO = 2500.0
KP = 1.0e6


def _impact(sim, gap_fn, n_max, approach_s):
    """Fly up to just before contact in one call, then step one at a time; return the contact
    duration, the overlap's sign changes interpolated within a step."""
    dt = sim.timestep_s
    sim.run(steps=max(int(approach_s / dt) - 3, 0))
    prev = gap_fn(sim)
    t_in = t_out = None
    for _ in range(n_max):
        sim.run(steps=1)
        g = gap_fn(sim)
        if t_in is None and g < 0 <= prev:
            t_in = sim.time_s - dt * (-g) / (prev - g)
        elif t_in is not None and g >= 0 > prev:
            t_out = sim.time_s - dt * g / (g - prev)
            break
        prev = g
    assert t_in is not None and t_out is not None
    return t_out - t_in


@pytest.mark.parametrize("xi", [0.1, 0.5])
def test_two_sphere_restitution_and_duration(xi):
    m = sphere_mass(R, RHO)
    kn = KP / 2.0
    w = math.sqrt(kn / (m / 2.0))
    t_c = math.pi / (w * math.sqrt(1.0 - xi * xi))
    cfg = config(mat_normal_stiffness_n_per_m=KP, mat_density_kg_m3=RHO, mat_damping_ratio_normal=xi,
                 mat_friction=0.0, gravity_m_s2=(0.0, 0.0, 0.0), timestep_s=t_c / 600.0)
    sim = Simulation(cfg)
    v0 = 0.2
    sim.add_spheres([[0.0, 0.0, 0.0], [2 * R + 1e-4, 0.0, 0.0]], [R, R], velocities_m_s=[[v0, 0, 0], [-v0, 0, 0]])
    gap = lambda s: np.linalg.norm(s.spheres.pos[1] - s.spheres.pos[0]) - 2 * R
    duration = _impact(sim, gap, 20000, 1e-4 / (2 * v0))
    v = sim.velocities_m_s()
    e = (v[1, 0] - v[0, 0]) / (2 * v0)
    e_theory = math.exp(-math.pi * xi / math.sqrt(1.0 - xi * xi))
    assert e == pytest.approx(e_theory, rel=0.01)
    assert duration == pytest.approx(t_c, rel=0.02)


def test_sphere_wall_restitution_uses_series_stiffness():
    xi = 0.3
    kw = 4.0e6
    m = sphere_mass(R, RHO)
    kn = KP * kw / (KP + kw)
    t_c = math.pi / (math.sqrt(kn / m) * math.sqrt(1.0 - xi * xi))
    cfg = config(mat_normal_stiffness_n_per_m=KP, mat_density_kg_m3=RHO, mat_damping_ratio_normal=xi,
                 gravity_m_s2=(0.0, 0.0, 0.0), timestep_s=t_c / 600.0)
    sim = Simulation(cfg)
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), normal_stiffness_n_per_m=kw, friction=0.0))
    sim.add_spheres([[0.0, 0.0, R + 1e-4]], [R], velocities_m_s=[[0.0, 0.0, -0.3]])
    duration = _impact(sim, lambda s: s.spheres.pos[0, 2] - R, 20000, 1e-4 / 0.3)
    e = sim.velocities_m_s()[0, 2] / 0.3
    assert e == pytest.approx(math.exp(-math.pi * xi / math.sqrt(1 - xi * xi)), rel=0.01)
    assert duration == pytest.approx(t_c, rel=0.02)
