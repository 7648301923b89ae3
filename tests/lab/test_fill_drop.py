"""The rainfall column's drop height: starting at the free-fall speed equals dropping from higher up."""
import math

import numpy as np
import pytest

from engine.config import MaterialSpec, SimulationConfig
from engine.lab.context import RunContext
from engine.lab.presets import THESIS
from engine.lab.procedures.fill import COLUMN_SOLID_FRACTION, drop_velocities_m_s
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
    # section 4.5.4: particles generated 0.1-4.7 m above the floor, a mean fall of 2.4 m. Our column
    # (fill_margin x the expected solid volume at COLUMN_SOLID_FRACTION over the container) is
    # uniform, so its mean height is half its height; with the drop height the mean fall must match.
    thesis_mean_fall_m = 0.5 * (0.1 + 4.7)
    column_height_m = THESIS.fill_margin * THESIS.expected_solid_fraction * THESIS.packing_height_m \
        / COLUMN_SOLID_FRACTION
    drop_m = RunContext.from_spec(JobSpec(fidelity="thesis")).rain_drop_height_m
    assert drop_m + 0.5 * column_height_m == pytest.approx(thesis_mean_fall_m, abs=0.1)
    assert RunContext.from_spec(JobSpec(fidelity="screening")).rain_drop_height_m == 0.0
    spec = JobSpec(fidelity="thesis", options={"fill_drop_height_m": 0.0})
    assert RunContext.from_spec(spec).rain_drop_height_m == 0.0
