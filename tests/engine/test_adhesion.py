"""The adhesive contact (engine.effects.cohesion_adhesive) against its analytic force law.

With a linear spring k and pull-off force F_c = 3/2 pi Gamma R*, the net normal force at overlap d is
-k d (tension) while k d < F_c and k d - 2 F_c beyond: most tensile, -F_c, at d_c = F_c / k, zero at
2 d_c, and the work to pull an unloaded contact (d = 2 d_c) apart is the area of the two triangles,
W = F_c d_c = F_c^2 / k.
"""
import math

import numpy as np
import pytest

from engine.config import EffectSpec, MaterialSpec, PlaneGeom, SimulationConfig, WallSpec
from engine.simulation import Simulation

from engine_helpers import sphere_mass

R = 0.01
RHO = 2500.0
KP = 1.0e6
KW = 1.0e7
KN_WALL = KP * KW / (KP + KW)
GAMMA = 50.0  # J/m2


def _config(gravity, damping_ratio_normal=0.5):
    return SimulationConfig(
        materials=[MaterialSpec(normal_stiffness_n_per_m=KP, density_kg_m3=RHO, friction=0.5,
                                damping_ratio_normal=damping_ratio_normal, damping_ratio_shear=0.5)],
        effects=[EffectSpec(name="cohesion_adhesive", params={"surface_energy_j_m2": GAMMA})],
        gravity_m_s2=gravity, safety_factor=0.2)


def _on_floor(gravity, overlap_m, damping_ratio_normal=0.5):
    sim = Simulation(_config(gravity, damping_ratio_normal))
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), normal_stiffness_n_per_m=KW, friction=0.5))
    sim.add_spheres([[0.0, 0.0, R - overlap_m]], [R])
    return sim


def _expected_net_force(overlap_m, k, f_c):
    elastic = k * overlap_m
    return elastic - 2.0 * np.minimum(elastic, f_c)


def test_force_follows_the_adhesive_branch_and_the_shifted_spring():
    f_c = 1.5 * math.pi * GAMMA * R  # a wall: R* is the sphere's radius
    d_c = f_c / KN_WALL
    overlaps = d_c * np.array([0.25, 0.5, 1.0, 1.5, 2.0, 3.0])
    forces = []
    for d in overlaps:
        sim = _on_floor((0.0, 0.0, 0.0), d)
        sim.run(steps=0)  # the forces of the initial state only
        forces.append(-sim.wall_force("floor")[2])  # force the floor takes = force pushing the sphere up
    np.testing.assert_allclose(forces, _expected_net_force(overlaps, KN_WALL, f_c), rtol=1e-9, atol=1e-12 * f_c)
    assert min(forces) == pytest.approx(-f_c, rel=1e-9)


@pytest.mark.parametrize("fraction, stays", [(0.5, True), (0.95, True), (1.05, False)])
def test_a_sphere_hangs_below_its_pull_off_force_and_falls_above_it(fraction, stays):
    """A body force pulling the sphere off the floor: below F_c it settles where k d - 2 F_c balances it."""
    f_c = 1.5 * math.pi * GAMMA * R
    m = sphere_mass(R, RHO)
    pull = fraction * f_c
    sim = _on_floor((0.0, 0.0, pull / m), 2.0 * f_c / KN_WALL, damping_ratio_normal=0.9)
    sim.run(duration_s=0.05)
    z = sim.positions_m()[0, 2]
    if stays:
        overlap = R - z
        assert overlap == pytest.approx((2.0 * f_c - pull) / KN_WALL, rel=1e-6)
    else:
        assert z > R


@pytest.mark.parametrize("fraction, separates", [(0.9, False), (1.1, True)])
def test_two_spheres_separate_when_their_kinetic_energy_exceeds_the_adhesion_work(fraction, separates):
    """Two equal spheres at rest at zero net force, then flung apart without damping: they part only
    if the relative kinetic energy 1/2 m_eff v^2 exceeds W = F_c^2 / k."""
    k = 0.5 * KP  # two particle springs in series
    f_c = 1.5 * math.pi * GAMMA * 0.5 * R
    m_eff = 0.5 * sphere_mass(R, RHO)
    v_rel = fraction * math.sqrt(2.0 * f_c * f_c / k / m_eff)
    sim = Simulation(_config((0.0, 0.0, 0.0), damping_ratio_normal=0.0))
    gap = 2.0 * R - 2.0 * f_c / k
    sim.add_spheres([[0.0, 0.0, 0.0], [gap, 0.0, 0.0]], [R, R])
    sim.set_velocities([[-0.5 * v_rel, 0.0, 0.0], [0.5 * v_rel, 0.0, 0.0]])
    period = 2.0 * math.pi * math.sqrt(m_eff / k)
    sim.run(duration_s=20.0 * period)
    distance = np.diff(sim.positions_m()[:, 0])[0]
    assert (distance > 2.0 * R) == separates
