"""Changing a material's friction between runs (packing prepared at one friction, tested at another)."""
import numpy as np
import pytest

from engine.simulation import Simulation
from tests.engine.engine_helpers import config


def _sliding_pair(friction: float) -> Simulation:
    """Two spheres pressed together along x, one sliding past the other along y: Coulomb sliding."""
    sim = Simulation(config(mat_friction=friction, mat_damping_ratio_normal=0.0, mat_damping_ratio_shear=0.0,
                            gravity_m_s2=(0.0, 0.0, 0.0)))
    sim.add_spheres(np.array([[0.0, 0.0, 0.0], [0.0195, 0.0, 0.0]]), [0.01, 0.01],
                    velocities_m_s=np.array([[0.0, 0.0, 0.0], [0.0, 8.0, 0.0]]))
    return sim


def _traction_ratio(sim: Simulation) -> float:
    """Tangential over normal impulse on the sliding sphere in one step, in the contact frame.

    At 8 m/s the tangential spring passes mu Fn within the first step, so from the third step on
    the contact slides and the ratio is the friction coefficient (within a few per cent: the normal turns ~2 % a step).
    """
    sim.run(steps=3)
    pos = sim.positions_m()
    normal = (pos[1] - pos[0]) / np.linalg.norm(pos[1] - pos[0])
    v0 = sim.velocities_m_s()[1].copy()
    sim.run(steps=1)
    dv = sim.velocities_m_s()[1] - v0
    dv_n = float(dv @ normal)
    return float(np.linalg.norm(dv - dv_n * normal)) / abs(dv_n)


def test_changed_friction_caps_the_sliding_traction_at_the_new_coefficient():
    sim = _sliding_pair(0.1)
    sim.set_material(0, friction=0.5)
    assert _traction_ratio(sim) == pytest.approx(0.5, rel=0.05)
    assert _traction_ratio(_sliding_pair(0.1)) == pytest.approx(0.1, rel=0.05)


def test_changed_friction_survives_a_checkpoint():
    sim = _sliding_pair(0.1)
    sim.set_material(0, friction=0.5)
    restored = Simulation.from_checkpoint(sim.checkpoint())
    assert restored.config.materials[0].friction == 0.5


def test_density_cannot_change_in_a_running_simulation():
    sim = _sliding_pair(0.1)
    with pytest.raises(ValueError, match="density_kg_m3"):
        sim.set_material(0, density_kg_m3=3000.0)
    with pytest.raises(ValueError, match="out of range"):
        sim.set_material(1, friction=0.2)
