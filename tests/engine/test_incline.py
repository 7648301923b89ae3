"""Sphere and double clump on an incline (gravity tilted over a level floor).

Analytic answers: a sphere rolls without slip at a = 5/7 g sin(a) while tan(a) < 7/2 mu, and slides
with a = g (sin(a) - mu cos(a)) beyond; a double clump lying down-slope cannot roll, so it stays
at rest while tan(a) < mu and slides with a = g (sin(a) - mu cos(a)) above.
"""
import math

import numpy as np
import pytest

from engine.config import PlaneGeom, WallSpec
from engine.particles.templates import double_clump
from engine.simulation import Simulation

from engine_helpers import G, config, fit_acceleration, tilted_gravity

R = 0.01
MU = 0.4


def _sim(angle_deg, mu_wall=MU):
    cfg = config(mat_normal_stiffness_n_per_m=2e6, mat_friction=MU, mat_damping_ratio_normal=0.7,
                 mat_damping_ratio_shear=0.7, gravity_m_s2=tilted_gravity(angle_deg), safety_factor=0.2)
    sim = Simulation(cfg)
    sim.add_wall(WallSpec(name="incline", geometry=PlaneGeom(), normal_stiffness_n_per_m=2e7, friction=mu_wall))
    return sim


def _track(sim, seconds, samples=40):
    t, x = [], []
    for _ in range(samples):
        sim.run(duration_s=seconds / samples)
        t.append(sim.time_s)
        x.append(sim.velocities_m_s()[0, 0])
    return np.array(t), np.array(x)


@pytest.mark.parametrize("angle_deg", [20.0, 30.0])
def test_sphere_rolls_at_five_sevenths_g_sin(angle_deg):
    assert math.tan(math.radians(angle_deg)) < 3.5 * MU
    sim = _sim(angle_deg)
    sim.add_spheres([[0.0, 0.0, R]], [R])
    sim.run(duration_s=0.02)  # contact settles in
    t, v = _track(sim, 0.1)
    a = fit_acceleration(t, v)
    assert a == pytest.approx(5.0 / 7.0 * G * math.sin(math.radians(angle_deg)), rel=0.01)
    # rolling without slip: v = omega R
    w = sim.angular_velocities_rad_s()[0, 1]
    assert w * R == pytest.approx(sim.velocities_m_s()[0, 0], rel=0.01)


def test_sphere_slides_when_friction_cannot_hold_rolling():
    angle = 60.0
    mu = 0.2
    assert math.tan(math.radians(angle)) > 3.5 * mu
    sim = _sim(angle, mu_wall=mu)
    sim.add_spheres([[0.0, 0.0, R]], [R])
    sim.run(duration_s=0.01)
    t, v = _track(sim, 0.05)
    a_theory = G * (math.sin(math.radians(angle)) - mu * math.cos(math.radians(angle)))
    assert fit_acceleration(t, v) == pytest.approx(a_theory, rel=0.01)


def _clump_on_incline(angle_deg):
    sim = _sim(angle_deg)
    tpl = double_clump(R, R, 1.0)  # long axis = body x = down-slope
    sim.add_bodies([tpl], [0], [[0.0, 0.0, R]])
    return sim


def test_double_clump_at_rest_below_friction_angle():
    angle = math.degrees(math.atan(MU)) - 3.0
    sim = _clump_on_incline(angle)
    sim.run(duration_s=0.05)
    x0 = sim.positions_m()[0, 0]
    sim.run(duration_s=0.3)
    assert abs(sim.positions_m()[0, 0] - x0) < 1e-5
    assert abs(sim.velocities_m_s()[0, 0]) < 1e-4


def test_double_clump_slides_above_friction_angle():
    angle = math.degrees(math.atan(MU)) + 5.0
    sim = _clump_on_incline(angle)
    sim.run(duration_s=0.02)
    t, v = _track(sim, 0.1)
    a_theory = G * (math.sin(math.radians(angle)) - MU * math.cos(math.radians(angle)))
    assert fit_acceleration(t, v) == pytest.approx(a_theory, rel=0.01)
    # it slides flat: no pitching
    assert np.abs(sim.angular_velocities_rad_s()[0]).max() < 1e-3
