"""Rotating walls, and walls added or removed under load.

Analytic answers: a rotating wall's geometry is the rigid rotation R(omega t) about its axis; a
flat-lying clump on a slowly tilting plane starts to slip when tan(tilt) = mu; a uniform sphere
rolling on a turntable spinning at Omega circles at 2/7 Omega (its velocity turns at that rate),
which needs the surface velocity omega x r at the contact. A wall added or removed must leave the
tangential springs of the other walls' contacts untouched.
"""
import math

import numpy as np
import pytest

from engine.config import MeshGeom, PlaneGeom, WallSpec
from engine.particles.templates import double_clump
from engine.simulation import Simulation

from engine_helpers import config, tilted_gravity

R = 0.01
MU = 0.4


def _rot(axis, angle):
    e = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -e[2], e[1]], [e[2], 0, -e[0]], [-e[1], e[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


def _square(half, z):
    a, b, c, d = [(-half, -half, z), (half, -half, z), (half, half, z), (-half, half, z)]
    return [[a, b, c], [a, c, d]]


def test_rotating_walls_follow_the_rigid_rotation():
    sim = Simulation(config(gravity_m_s2=(0.0, 0.0, 0.0)))
    sim.add_spheres([[5.0, 5.0, 5.0]], [R])  # far from both walls
    centre = np.array([0.1, -0.2, 0.0])
    omega = np.array([0.3, -0.2, 0.9])
    tri0 = np.array(_square(0.05, 0.02))
    sim.add_wall(WallSpec(name="plate", geometry=MeshGeom(triangles_m=tri0.tolist()),
                          angular_velocity_rad_s=tuple(omega), rotation_centre_m=tuple(centre)))
    sim.add_wall(WallSpec(name="tilt", geometry=PlaneGeom(point_m=(0.0, 0.0, 0.1), normal=(0.0, 0.0, 1.0)),
                          angular_velocity_rad_s=(0.5, 0.0, 0.0)))
    n = sim.run(duration_s=0.2)
    t = n * sim.timestep_s
    rot = _rot(omega, np.linalg.norm(omega) * t)
    expected = (tri0 - centre) @ rot.T + centre
    assert np.allclose(sim.wall_triangles("plate"), expected, atol=1e-9)
    # the plane turns about an axis through its own point: normal = R_x(0.5 t) z
    assert np.allclose(sim.wall_frame("tilt")[2], _rot((1, 0, 0), 0.5 * t) @ [0, 0, 1], atol=1e-9)
    assert np.allclose(sim.wall_position("tilt"), [0.0, 0.0, 0.1], atol=1e-12)


def test_clump_on_tilting_plane_slips_at_the_friction_angle():
    rate = 0.4  # rad/s: slow enough that the clump's own inertia is negligible
    cfg = config(mat_normal_stiffness_n_per_m=2e6, mat_friction=MU, mat_damping_ratio_normal=0.7,
                 mat_damping_ratio_shear=0.7, safety_factor=0.2)
    sim = Simulation(cfg)
    sim.add_wall(WallSpec(name="table", geometry=PlaneGeom(), normal_stiffness_n_per_m=2e7, friction=MU))
    sim.add_bodies([double_clump(R, R, 1.0)], [0], [[0.0, 0.0, R]])  # long axis along x: cannot roll
    sim.run(duration_s=0.05)  # settle on the level table
    sim.set_wall_rotation("table", (0.0, rate, 0.0))  # tilts about y: down-slope is along the table's x
    t_start = sim.time_s
    slip_angle = None
    while sim.time_s - t_start < 1.2:
        sim.run(duration_s=0.002)
        # velocity relative to the table surface under the clump (the table turns about the origin)
        slip = sim.velocities_m_s()[0] - np.cross((0.0, rate, 0.0), sim.positions_m()[0])
        if np.linalg.norm(slip) > 2e-3:
            slip_angle = rate * (sim.time_s - t_start)
            break
    assert slip_angle is not None, "the clump never slipped"
    # slip starts at atan(mu) = 21.8 deg; past it the slip speed grows as ~ g rate t, so 2 mm/s follows at once
    assert math.degrees(slip_angle) == pytest.approx(math.degrees(math.atan(MU)), abs=1.0)


@pytest.mark.slow
def test_sphere_on_turntable_circles_at_two_sevenths_of_its_rate():
    spin = 2.0  # rad/s
    cfg = config(mat_normal_stiffness_n_per_m=2e6, mat_friction=0.8, mat_damping_ratio_normal=0.7,
                 mat_damping_ratio_shear=0.7, safety_factor=0.2)
    sim = Simulation(cfg)
    sim.add_wall(WallSpec(name="turntable", geometry=PlaneGeom(), normal_stiffness_n_per_m=2e7, friction=0.8,
                          angular_velocity_rad_s=(0.0, 0.0, spin)))
    sim.add_spheres([[0.05, 0.0, R]], [R])
    sim.run(duration_s=0.3)  # the initial slip ends within milliseconds; then it rolls
    t, heading = [], []
    for _ in range(60):
        sim.run(duration_s=0.02)
        v = sim.velocities_m_s()[0]
        t.append(sim.time_s)
        heading.append(math.atan2(v[1], v[0]))
    rate = np.polyfit(t, np.unwrap(heading), 1)[0]
    assert rate == pytest.approx(2.0 / 7.0 * spin, rel=0.01)


def _hist_by_key(sim, wall):
    w = sim.wall_index(wall)
    wc = sim.wall_contacts
    sphere = np.repeat(np.arange(wc.start.shape[0] - 1), np.diff(wc.start))
    return {(int(s), int(t) - int(sim.walls.tri_start[w]) if t >= 0 else -1): wc.hist[e].copy()
            for e, (s, ww, t) in enumerate(zip(sphere, wc.wall, wc.tri)) if ww == w and wc.k[e] > 0}


def test_adding_and_removing_walls_keeps_the_other_contacts_history():
    angle = math.degrees(math.atan(MU)) - 5.0  # held by friction: the springs carry the load
    cfg = config(mat_normal_stiffness_n_per_m=2e6, mat_friction=MU, mat_damping_ratio_normal=0.7,
                 mat_damping_ratio_shear=0.7, gravity_m_s2=tilted_gravity(angle), safety_factor=0.2)
    sim = Simulation(cfg)
    sim.add_wall(WallSpec(name="far", geometry=PlaneGeom(point_m=(0.0, 0.0, 1.0), normal=(0.0, 0.0, -1.0))))
    sim.add_wall(WallSpec(name="floor", geometry=MeshGeom(triangles_m=_square(0.2, 0.0)),
                          normal_stiffness_n_per_m=2e7, friction=MU))
    sim.add_bodies([double_clump(R, R, 1.0)], [0], [[0.0, 0.0, R]])
    sim.run(duration_s=0.1)
    before = _hist_by_key(sim, "floor")
    assert before and all(np.linalg.norm(h[:3]) > 0 for h in before.values())
    sim.add_wall(WallSpec(name="lid", geometry=PlaneGeom(point_m=(0.0, 0.0, 0.5), normal=(0.0, 0.0, -1.0))))
    sim.remove_wall("far")  # the floor's index and its triangles' ids all shift down
    sim.run(steps=1)  # rebuild the lists; one step moves the springs by ~nothing
    after = _hist_by_key(sim, "floor")
    assert after.keys() == before.keys()
    for key, h in before.items():
        assert np.allclose(after[key][:3], h[:3], rtol=1e-3, atol=1e-12)
    with pytest.raises(KeyError):
        sim.wall_index("far")
