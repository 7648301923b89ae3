"""The rainfall column's drop height: starting at the free-fall speed equals dropping from higher up."""
import math

import numpy as np

from engine.config import MaterialSpec, SimulationConfig
from engine.lab.context import RunContext
from engine.lab.procedures.fill import drop_velocities_m_s
from engine.lab.spec import JobSpec
from engine.simulation import Simulation

G = 9.81


def test_dropped_column_matches_free_fall_from_the_drop_height():
    drop_m, z0_m, radius_m = 1.9, 0.8, 0.01
    sim = Simulation(SimulationConfig(materials=[MaterialSpec(density_kg_m3=2500.0)], gravity_m_s2=(0, 0, -G)))
    positions = np.array([[0.0, 0.0, z0_m], [0.1, 0.0, z0_m + 0.3]])
    sim.add_spheres(positions, [radius_m, radius_m], velocities_m_s=drop_velocities_m_s(2, drop_m))
    sim.run(duration_s=0.2)
    t = sim.time_s
    # a body released at rest drop_m higher has fallen drop_m after sqrt(2 drop_m / g), then t more
    t_release = math.sqrt(2 * drop_m / G) + t
    expected_z = positions[:, 2] + drop_m - 0.5 * G * t_release ** 2
    np.testing.assert_allclose(sim.positions_m()[:, 2], expected_z, atol=1e-6)
    np.testing.assert_allclose(sim.velocities_m_s()[:, 2], -G * t_release, rtol=1e-9)


def test_thesis_fill_drops_from_the_thesis_column_mean_height():
    # section 4.5.4: particles generated 0.1-4.7 m above the floor; our ~1 m column's mean height is
    # ~0.5 m, so 1.9 m more gives the thesis's mean fall of ~2.4 m
    assert RunContext.from_spec(JobSpec(fidelity="thesis")).rain_drop_height_m == 1.9
    assert RunContext.from_spec(JobSpec(fidelity="screening")).rain_drop_height_m == 0.0
    spec = JobSpec(fidelity="thesis", options={"fill_drop_height_m": 0.0})
    assert RunContext.from_spec(spec).rain_drop_height_m == 0.0
