"""Internal renumbering in cell order changes memory layout, not physics, and not the public ids.

A settled, frictional bed (loaded tangential springs) run on with and without renumbering at every
rebuild: public positions, masses and template ids agree to round-off. Losing a spring, or giving a
swapped pair (i > j after renumbering) the wrong sign, would move spheres by ~ mu fn / ks ~ 1e-5 m.
"""
import numpy as np

from engine.config import CylinderGeom, PlaneGeom, WallSpec
from engine.simulation import Simulation

from engine_helpers import config

R = 0.01


def _shuffled_bed(reorder_every):
    cfg = config(mat_normal_stiffness_n_per_m=1e5, mat_friction=0.5, mat_damping_ratio_shear=0.0,
                 reorder_every_rebuilds=reorder_every)
    sim = Simulation(cfg)
    rng = np.random.default_rng(7)
    g = (np.arange(6) - 2.5) * 2.4 * R
    pos = np.array([[x, y, 0.02 + 2.4 * R * k] for k in range(6) for x in g for y in g])
    order = rng.permutation(len(pos))  # inserted in random order, as rainfall does
    radii = rng.uniform(0.8 * R, R, len(pos))
    sim.add_spheres(pos[order] + rng.uniform(-0.1 * R, 0.1 * R, pos.shape) * [1, 1, 0], radii)
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), normal_stiffness_n_per_m=1e7))
    sim.add_wall(WallSpec(name="tube", geometry=CylinderGeom(base_m=(0, 0, -0.01), radius_m=0.09, height_m=0.5)))
    return sim


def test_renumbering_keeps_physics_and_public_ids():
    settled = _shuffled_bed(0)
    settled.run(duration_s=0.3)  # fall and settle: the springs carry load
    state = settled.checkpoint()
    plain, ordered = _shuffled_bed(0), _shuffled_bed(1)
    for sim in (plain, ordered):
        sim.restore(state)
    for _ in range(10):  # force rebuilds (and, for `ordered`, renumbering) while under load
        for sim in (plain, ordered):
            sim._stale = True
            sim.run(steps=50)
    assert not np.array_equal(ordered._body_user, np.arange(ordered.n_bodies))  # it was renumbered
    assert np.abs(plain.positions_m() - ordered.positions_m()).max() < 1e-10
    assert np.array_equal(plain.body_masses_kg(), ordered.body_masses_kg())
    assert np.array_equal(plain.sphere_radii_m(), ordered.sphere_radii_m())
    assert np.array_equal(plain.sphere_body_ids(), ordered.sphere_body_ids())
    floor = plain.wall_force("floor")
    assert np.abs(floor - ordered.wall_force("floor")).max() < 1e-6 * abs(floor[2])
