"""Each contact effect against its model's analytic answer.

All effect tests share one kernel with every effect compiled in (config.compiled_effects) and
switch effects on per pair, which also checks that an effect compiled in but off changes nothing.
"""
import math

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from engine.config import EffectSpec, MaterialSpec, PlaneGeom, SimulationConfig, WallSpec
from engine.effects import REGISTRY
from engine.simulation import Simulation

from engine_helpers import G, sphere_mass

ALL = sorted(REGISTRY)
R = 0.01
RHO = 2500.0
KP = 1.0e6
KW = 1.0e7


def _sim(effects, gravity=(0.0, 0.0, -G), **mat):
    m = dict(normal_stiffness_n_per_m=KP, density_kg_m3=RHO, friction=0.5, damping_ratio_normal=0.5,
             damping_ratio_shear=0.5)
    m.update(mat)
    cfg = SimulationConfig(materials=[MaterialSpec(**m)], effects=effects, compiled_effects=ALL,
                           gravity_m_s2=gravity, safety_factor=0.2)
    sim = Simulation(cfg)
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), normal_stiffness_n_per_m=KW, friction=0.5))
    return sim


def _roll_distance(sim, v0):
    """Distance rolled until the sphere's velocity first reaches zero."""
    x0 = sim.positions_m()[0, 0]
    prev_x = x0
    for _ in range(200000):
        sim.run(steps=20)
        v = sim.velocities_m_s()[0, 0]
        x = sim.positions_m()[0, 0]
        if v <= 0.0:
            return x - x0
        prev_x = x
    raise AssertionError("sphere never stopped")


@pytest.mark.parametrize("name", ["rolling_epsd", "rolling_epsd2", "rolling_constant_torque"])
def test_rolling_resistance_stops_at_predicted_distance(name):
    mu_r = 0.05
    v0 = 0.3
    sim = _sim([EffectSpec(name=name, params={"rolling_friction": mu_r}, contact_types=["particle-wall"])])
    m = sphere_mass(R, RHO)
    kn = KP * KW / (KP + KW)
    sim.add_spheres([[0.0, 0.0, R - m * G / kn]], [R])
    sim.run(duration_s=0.01)  # seat the contact
    sim.set_velocities([[v0, 0.0, 0.0]], [[0.0, v0 / R, 0.0]])
    # torque mu_r R m g against rolling: (m + I/R^2) a = mu_r m g -> a = 5/7 mu_r g
    predicted = v0 ** 2 / (2.0 * 5.0 / 7.0 * mu_r * G)
    assert _roll_distance(sim, v0) == pytest.approx(predicted, rel=0.02)


def test_without_rolling_resistance_the_sphere_keeps_rolling():
    sim = _sim([])
    m = sphere_mass(R, RHO)
    sim.add_spheres([[0.0, 0.0, R - m * G / (KP * KW / (KP + KW))]], [R])
    sim.run(duration_s=0.01)
    sim.set_velocities([[0.3, 0.0, 0.0]], [[0.0, 0.3 / R, 0.0]])
    sim.run(duration_s=0.2)
    assert sim.velocities_m_s()[0, 0] == pytest.approx(0.3, rel=1e-3)


def _hertz_params():
    return {"young_modulus_pa": 5e7, "poisson_ratio": 0.25, "wall_young_modulus_pa": 2e11,
            "wall_poisson_ratio": 0.3}


def _e_star(p):
    return 1.0 / ((1 - p["poisson_ratio"] ** 2) / p["young_modulus_pa"]
                  + (1 - p["wall_poisson_ratio"] ** 2) / p["wall_young_modulus_pa"])


def test_hertz_force_scales_with_overlap_to_three_halves():
    p = _hertz_params()
    forces = []
    overlaps = np.array([1e-5, 4e-5, 1.6e-4])
    for delta in overlaps:
        sim = _sim([EffectSpec(name="hertz_mindlin", params=p)], gravity=(0.0, 0.0, 0.0))
        sim.add_spheres([[0.0, 0.0, R - delta]], [R])
        sim.run(steps=0)  # forces of the initial state only
        forces.append(sim.wall_force("floor")[2])
    forces = -np.array(forces)  # the wall is pushed down
    expected = 4.0 / 3.0 * _e_star(p) * math.sqrt(R) * overlaps ** 1.5
    np.testing.assert_allclose(forces, expected, rtol=1e-6)
    slope = np.polyfit(np.log(overlaps), np.log(forces), 1)[0]
    assert slope == pytest.approx(1.5, rel=0.01)


def _pull_off_force(kc, e_star):
    """SJKR on Hertz, sphere on a plane: max over overlap of k_c pi (2 R d - d^2) - 4/3 E* sqrt(R) d^1.5."""
    net = lambda d: -(kc * math.pi * (2 * R * d - d * d) - 4.0 / 3.0 * e_star * math.sqrt(R) * d ** 1.5)
    res = minimize_scalar(net, bounds=(1e-12, R), method="bounded", options={"xatol": 1e-14})
    return -res.fun, res.x


@pytest.mark.parametrize("fraction, stays", [(0.95, True), (1.05, False)])
def test_cohesive_pull_off_force_matches_model(fraction, stays):
    p = _hertz_params()
    kc = 2.0e5
    f_max, d_star = _pull_off_force(kc, _e_star(p))
    m = sphere_mass(R, RHO)
    g_up = fraction * f_max / m  # a body force pulling the sphere off the floor
    effects = [EffectSpec(name="hertz_mindlin", params=p),
               EffectSpec(name="cohesion_sjkr", params={"cohesion_energy_density_j_m3": kc})]
    sim = _sim(effects, gravity=(0.0, 0.0, g_up), damping_ratio_normal=0.9)
    sim.add_spheres([[0.0, 0.0, R - d_star]], [R])
    sim.run(duration_s=0.05)
    attached = sim.positions_m()[0, 2] < R
    assert attached == stays
