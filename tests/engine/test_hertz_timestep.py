"""The critical step of a Hertzian contact: its damped, rotating tangential mode, against closed forms.

The tangential mode of two spheres in contact turns them as well as sliding them: 1 / m_t = 1 / m_eff + r^2 / I
for each sphere, so with a solid sphere's I = 2/5 m r^2 its mass is 2/7 of the translational one and, with
LIGGGHTS' dashpot sized on the translational mass, its damping ratio is sqrt(7/2) times the nominal. Velocity
Verlet with a dashpot is stable for w dt < 2 (sqrt(1 + z^2) - z). Hertz-Mindlin's tangential stiffness at an
overlap delta is 8 G* sqrt(R* delta). The engine's step must be 0.3 of that bound at 1 % of the radius.

And what the bound is for: two spheres stacked between a floor and a fixed lid at E 4 GPa, every contact at 2 %
overlap (a fill's impacts reach about 4 %), sliding past each other: every mode is damped, so at a stable step the
motion dies out. At the engine's step it does; at 0.3 x Rayleigh's step, the step the engine took before, the
spheres end up moving faster than they started (the stiff corner's fill that never came to rest, docs/lab.md).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from engine.config import EffectSpec, MaterialSpec, PlaneGeom, SimulationConfig, WallSpec
from engine.simulation import Simulation

E_PA, NU, RADIUS_M, DENSITY = 4.0e9, 0.25, 0.02, 2300.0
DAMPING = 0.8


def _config(timestep_s=None):
    return SimulationConfig(
        materials=[MaterialSpec(normal_stiffness_n_per_m=1e6, density_kg_m3=DENSITY, friction=1.0,
                                damping_ratio_normal=DAMPING, damping_ratio_shear=DAMPING)],
        effects=[EffectSpec(name="hertz_mindlin", params={"young_modulus_pa": E_PA, "poisson_ratio": NU})],
        gravity_m_s2=(0.0, 0.0, 0.0), threads=1, timestep_s=timestep_s)


def _pair(timestep_s=None):
    """Two spheres side by side, free: enough for the time step's report."""
    sim = Simulation(_config(timestep_s))
    sim.add_spheres([[0.0, 0.0, 0.0], [2.5 * RADIUS_M, 0.0, 0.0]], [RADIUS_M, RADIUS_M])
    return sim


def _stack(timestep_s=None, overlap_fraction=0.02):
    """Two spheres stacked between a floor and a fixed lid, every contact at ``overlap_fraction`` of a radius, the
    spheres sliding past each other at 0.05 m/s: a confined contact network, as in a packing, at rest only once
    the dashpots have taken the motion out."""
    sim = Simulation(_config(timestep_s))
    d = overlap_fraction * RADIUS_M
    z1 = RADIUS_M - d
    z2 = z1 + 2 * RADIUS_M - d
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), friction=1.0))
    sim.add_wall(WallSpec(name="lid", geometry=PlaneGeom(point_m=(0.0, 0.0, z2 + RADIUS_M - d), normal=(0.0, 0.0, -1.0)),
                          friction=1.0))
    sim.add_spheres([[0.0, 0.0, z1], [0.0, 0.0, z2]], [RADIUS_M, RADIUS_M])
    sim.set_velocities(np.array([[0.05, 0.0, 0.0], [-0.05, 0.0, 0.0]]), np.zeros((2, 3)))
    return sim


def _tangential_bound_s(overlap_fraction):
    g = E_PA / (2 * (1 + NU))
    g_star = 1.0 / (2 * (2 - NU) / g)
    r_star = RADIUS_M / 2
    k_t = 8 * g_star * math.sqrt(r_star * overlap_fraction * RADIUS_M)
    m = DENSITY * 4 / 3 * math.pi * RADIUS_M**3
    m_eff = m / 2
    rot = 1 + m * RADIUS_M**2 / (0.4 * m * RADIUS_M**2)  # 3.5
    omega, zeta = math.sqrt(k_t * rot / m_eff), DAMPING * math.sqrt(rot)
    return 2 * (math.sqrt(1 + zeta**2) - zeta) / omega


def test_the_step_is_three_tenths_of_the_damped_tangential_bound_at_one_percent():
    report = _pair().timestep_report()
    assert report.limiting_mode == "hertz_mindlin particle-particle tangential"
    assert report.critical_s == pytest.approx(_tangential_bound_s(0.01), rel=1e-9)
    assert report.timestep_s == pytest.approx(0.3 * _tangential_bound_s(0.01), rel=1e-9)


DURATION_S = 0.05  # every mode damped at 0.8 of critical or more, the slowest e-folding in well under 1 ms


def test_a_confined_stiff_contact_comes_to_rest_at_the_engines_step():
    sim = _stack()
    start = sim.kinetic_energy()
    sim.run(duration_s=DURATION_S)
    # after some hundred e-foldings of a stable damped system nothing is left of the motion
    assert sim.kinetic_energy() < 1e-12 * start


def test_at_three_tenths_of_rayleighs_step_the_same_contacts_run_away():
    g = E_PA / (2 * (1 + NU))
    rayleigh = math.pi * RADIUS_M * math.sqrt(DENSITY / g) / (0.1631 * NU + 0.8766)
    assert 0.3 * rayleigh > _tangential_bound_s(0.02)  # past the bound at this overlap
    sim = _stack(timestep_s=0.3 * rayleigh)  # below the engine's critical step (at 1 %), so it is accepted
    start = sim.kinetic_energy()
    sim.run(duration_s=DURATION_S)
    # not at rest, and moving more than it was given: the integrator feeds the tangential mode
    assert sim.kinetic_energy() > start
