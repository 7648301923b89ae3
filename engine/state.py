"""Array containers handed to the numba kernels (structure of arrays, float64, C order).

namedtuples keep the kernel signatures short and still cache; inside a ``prange`` body always read
fields into locals first (numba mis-handles tuple attribute access there).
"""
from __future__ import annotations

from collections import namedtuple

import numpy as np

Bodies = namedtuple("Bodies", [
    "pos", "vel", "quat", "omega", "mass", "inertia", "force", "torque",
    "sphere_start", "is_clump", "local_damping",
])
Spheres = namedtuple("Spheres", [
    "body", "offset", "radius", "pos", "vel", "material", "kp", "force", "torque", "pos_at_build",
])
Walls = namedtuple("Walls", [
    "kind", "origin", "frame", "par", "kn", "mu", "material", "vel", "vel_target", "ramp_time", "ramp_start",
    "mode", "servo_axis", "servo_target", "servo_vmax", "servo_gain", "tri", "tri_start", "box_lo", "box_hi",
    "force", "moment", "k_sum", "origin_at_build", "omega", "centre", "reach", "swept",
])
# per pair: spheres i < j, history row, constants [kn, m_eff, sqrt(kn m_eff)] (engine/blocks.py) and the
# contact's normal stiffness at the last force evaluation (0: not touching); per sphere: CSR row starts and
# the force/torque accumulator [f(3), t(3)] the pair pass adds into (read and cleared by the body pass);
# block_start: the pair-row blocks of engine/blocks.py
Pairs = namedtuple("Pairs", ["i", "j", "row_start", "hist", "const", "k", "acc", "block_start"])
WallContacts = namedtuple("WallContacts", ["start", "wall", "tri", "hist", "force", "point", "k"])

MODE_KINEMATIC, MODE_SERVO = 0, 1


def empty_bodies() -> Bodies:
    z3 = np.zeros((0, 3))
    return Bodies(z3, z3.copy(), np.zeros((0, 4)), z3.copy(), np.zeros(0), z3.copy(), z3.copy(), z3.copy(),
                  np.zeros(1, np.int64), np.zeros(0, np.bool_), np.zeros(0))


def empty_spheres() -> Spheres:
    z3 = np.zeros((0, 3))
    return Spheres(np.zeros(0, np.int64), z3, np.zeros(0), z3.copy(), z3.copy(), np.zeros(0, np.int64),
                   np.zeros(0), z3.copy(), z3.copy(), z3.copy())


def empty_pairs(n_spheres: int, n_hist: int) -> Pairs:
    z = np.zeros(0, np.int64)
    return Pairs(z, z.copy(), np.zeros(n_spheres + 1, np.int64), np.zeros((0, n_hist)), np.zeros((0, 3)),
                 np.zeros(0), np.zeros((n_spheres, 6)), np.array([0, n_spheres], np.int64))


def empty_wall_contacts(n_spheres: int, n_hist: int) -> WallContacts:
    z = np.zeros(0, np.int64)
    return WallContacts(np.zeros(n_spheres + 1, np.int64), z, z.copy(), np.zeros((0, n_hist)),
                        np.zeros((0, 3)), np.zeros((0, 3)), np.zeros(0))
