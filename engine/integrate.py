"""Velocity-Verlet integration of rigid bodies; clumps rotate with quaternions.

Translation: half kick, drift, forces, half kick. Rotation of a clump: the world angular momentum
takes the torque kicks and omega = R I^-1 R^T L; the quaternion turns by the exact rotation of angle
|omega| dt. A single sphere (isotropic inertia) skips all quaternion work.
"""
from __future__ import annotations

import math

from numba import njit, prange


@njit(cache=True)
def _rot(q, v0, v1, v2):
    """R(q) v for a unit quaternion q = (w, x, y, z), body -> world."""
    w, x, y, z = q[0], q[1], q[2], q[3]
    # t = 2 q_vec x v ; v' = v + w t + q_vec x t
    t0 = 2.0 * (y * v2 - z * v1)
    t1 = 2.0 * (z * v0 - x * v2)
    t2 = 2.0 * (x * v1 - y * v0)
    return (v0 + w * t0 + (y * t2 - z * t1), v1 + w * t1 + (z * t0 - x * t2), v2 + w * t2 + (x * t1 - y * t0))


@njit(cache=True)
def _rot_t(q, v0, v1, v2):
    """R(q)^T v (world -> body)."""
    w, x, y, z = q[0], -q[1], -q[2], -q[3]
    t0 = 2.0 * (y * v2 - z * v1)
    t1 = 2.0 * (z * v0 - x * v2)
    t2 = 2.0 * (x * v1 - y * v0)
    return (v0 + w * t0 + (y * t2 - z * t1), v1 + w * t1 + (z * t0 - x * t2), v2 + w * t2 + (x * t1 - y * t0))


@njit(cache=True, inline='always')
def kick_body(b, vel, quat, omega, mass, inertia, force, torque, is_clump, dt_half):
    s = dt_half / mass[b]
    vel[b, 0] += s * force[b, 0]
    vel[b, 1] += s * force[b, 1]
    vel[b, 2] += s * force[b, 2]
    if is_clump[b]:
        q = quat[b]
        a0, a1, a2 = _rot_t(q, omega[b, 0], omega[b, 1], omega[b, 2])
        l0, l1, l2 = inertia[b, 0] * a0, inertia[b, 1] * a1, inertia[b, 2] * a2
        l0, l1, l2 = _rot(q, l0, l1, l2)
        l0 += dt_half * torque[b, 0]
        l1 += dt_half * torque[b, 1]
        l2 += dt_half * torque[b, 2]
        a0, a1, a2 = _rot_t(q, l0, l1, l2)
        omega[b, 0], omega[b, 1], omega[b, 2] = _rot(q, a0 / inertia[b, 0], a1 / inertia[b, 1], a2 / inertia[b, 2])
    else:
        s = dt_half / inertia[b, 0]
        omega[b, 0] += s * torque[b, 0]
        omega[b, 1] += s * torque[b, 1]
        omega[b, 2] += s * torque[b, 2]


@njit(cache=True, parallel=True)
def drift(pos, vel, quat, omega, is_clump, sphere_start, offset, s_pos, s_vel, dt):
    for b in prange(pos.shape[0]):
        drift_body(b, pos, vel, quat, omega, is_clump, sphere_start, offset, s_pos, s_vel, dt)


@njit(cache=True, inline='always')
def drift_body(b, pos, vel, quat, omega, is_clump, sphere_start, offset, s_pos, s_vel, dt):
    pos[b, 0] += dt * vel[b, 0]
    pos[b, 1] += dt * vel[b, 1]
    pos[b, 2] += dt * vel[b, 2]
    if is_clump[b]:
        w0, w1, w2 = omega[b, 0], omega[b, 1], omega[b, 2]
        wn = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        if wn > 0.0:
            half = 0.5 * wn * dt
            c = math.cos(half)
            s = math.sin(half) / wn
            d0, d1, d2, d3 = c, s * w0, s * w1, s * w2
            q0, q1, q2, q3 = quat[b, 0], quat[b, 1], quat[b, 2], quat[b, 3]
            n0 = d0 * q0 - d1 * q1 - d2 * q2 - d3 * q3
            n1 = d0 * q1 + d1 * q0 + d2 * q3 - d3 * q2
            n2 = d0 * q2 - d1 * q3 + d2 * q0 + d3 * q1
            n3 = d0 * q3 + d1 * q2 - d2 * q1 + d3 * q0
            norm = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2 + n3 * n3)
            quat[b, 0], quat[b, 1], quat[b, 2], quat[b, 3] = n0 / norm, n1 / norm, n2 / norm, n3 / norm
        for k in range(sphere_start[b], sphere_start[b + 1]):
            r0, r1, r2 = _rot(quat[b], offset[k, 0], offset[k, 1], offset[k, 2])
            s_pos[k, 0] = pos[b, 0] + r0
            s_pos[k, 1] = pos[b, 1] + r1
            s_pos[k, 2] = pos[b, 2] + r2
            s_vel[k, 0] = vel[b, 0] + w1 * r2 - w2 * r1
            s_vel[k, 1] = vel[b, 1] + w2 * r0 - w0 * r2
            s_vel[k, 2] = vel[b, 2] + w0 * r1 - w1 * r0
    else:
        k = sphere_start[b]
        s_pos[k, 0], s_pos[k, 1], s_pos[k, 2] = pos[b, 0], pos[b, 1], pos[b, 2]
        s_vel[k, 0], s_vel[k, 1], s_vel[k, 2] = vel[b, 0], vel[b, 1], vel[b, 2]
