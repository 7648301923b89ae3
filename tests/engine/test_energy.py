"""Energy conservation of an undamped, frictionless dense packing (no gravity) in a box of planes.

E = kinetic + sum over contacts of kn delta^2 / 2 (particle pairs kn = kp / 2, walls kp kw / (kp + kw)),
computed here from positions with numpy, independently of the engine.
"""
import numpy as np

from engine.config import PlaneGeom, WallSpec
from engine.simulation import Simulation

from engine_helpers import config

R = 0.01
KP = 1.0e5
KW = 1.0e6
HALF = 0.05


def _potential(pos, radii):
    d = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)
    overlap = radii[:, None] + radii[None, :] - d
    iu = np.triu_indices(len(pos), 1)
    ov = np.clip(overlap[iu], 0.0, None)
    e = 0.5 * (KP / 2.0) * np.sum(ov ** 2)
    kw = KP * KW / (KP + KW)
    for axis in range(3):
        for sign in (-1.0, 1.0):
            ov_w = np.clip(radii - (HALF - sign * pos[:, axis]), 0.0, None)
            e += 0.5 * kw * np.sum(ov_w ** 2)
    return e


def test_energy_conserved_over_1e5_steps():
    cfg = config(mat_normal_stiffness_n_per_m=KP, mat_friction=0.0, mat_damping_ratio_normal=0.0,
                 mat_damping_ratio_shear=0.0, gravity_m_s2=(0.0, 0.0, 0.0), safety_factor=0.05)
    sim = Simulation(cfg)
    rng = np.random.default_rng(7)
    g = np.linspace(-HALF + 0.95 * R, HALF - 0.95 * R, 4)
    pos = np.array([[x, y, z] for x in g for y in g for z in g]) + rng.normal(0, 0.02 * R, (64, 3))
    radii = rng.uniform(1.25 * R, 1.45 * R, len(pos))  # dense: most neighbours overlap
    sim.add_spheres(pos, radii, velocities_m_s=rng.normal(0.0, 0.05, (len(pos), 3)))
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = [0.0, 0.0, 0.0]
            n[axis] = -sign
            p = [0.0, 0.0, 0.0]
            p[axis] = sign * HALF
            sim.add_wall(WallSpec(name=f"w{axis}{int(sign)}", geometry=PlaneGeom(point_m=tuple(p), normal=tuple(n)),
                                  normal_stiffness_n_per_m=KW, friction=0.0))
    e0 = sim.kinetic_energy() + _potential(sim.sphere_positions_m(), radii)
    assert _potential(sim.sphere_positions_m(), radii) > 0.3 * e0  # genuinely dense
    energies = []
    for _ in range(10):
        sim.run(steps=10_000)
        energies.append(sim.kinetic_energy() + _potential(sim.sphere_positions_m(), radii))
    assert sim.step == 100_000
    drift = np.max(np.abs(np.array(energies) - e0)) / e0
    assert drift < 1e-3
