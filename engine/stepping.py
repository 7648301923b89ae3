"""Per-step helpers independent of the contact law: body sums, wall motion, wall resultants."""
from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, inline='always')
def sign(x):
    """+1.0, -1.0 or 0.0 as np.sign, branch-free."""
    return (x > 0.0) * 1.0 - (x < 0.0) * 1.0


@njit(cache=True, inline='always')
def damped(f, a, v):
    """Cundall's non-viscous damping of one component: f reduced by a|f| against the motion v.
    Branch-free (a = 0 leaves f as it is) and on scalars only, so it inlines into the body pass's loops
    without reference counting."""
    return f - a * abs(f) * sign(v)


@njit(cache=True, inline='always')
def body_sum(b, b_pos, b_vel, b_omega, b_mass, b_force, b_torque, sphere_start, is_clump, local_damping,
             s_pos, s_force, s_torque, g0, g1, g2):
    """Resultant force (with gravity) and torque of body b from its spheres, then local damping."""
    m = b_mass[b]
    f0, f1, f2 = m * g0, m * g1, m * g2
    t0 = t1 = t2 = 0.0
    for k in range(sphere_start[b], sphere_start[b + 1]):
        f0 += s_force[k, 0]
        f1 += s_force[k, 1]
        f2 += s_force[k, 2]
        t0 += s_torque[k, 0]
        t1 += s_torque[k, 1]
        t2 += s_torque[k, 2]
        if is_clump[b]:
            r0 = s_pos[k, 0] - b_pos[b, 0]
            r1 = s_pos[k, 1] - b_pos[b, 1]
            r2 = s_pos[k, 2] - b_pos[b, 2]
            t0 += r1 * s_force[k, 2] - r2 * s_force[k, 1]
            t1 += r2 * s_force[k, 0] - r0 * s_force[k, 2]
            t2 += r0 * s_force[k, 1] - r1 * s_force[k, 0]
    # Cundall's non-viscous damping, branch-free (`damped`): a branch here kept numba from pruning the
    # reference counting of the array arguments, which cost ~70 ns per body when inlined in the body pass.
    a = local_damping[b]
    f0, f1, f2 = damped(f0, a, b_vel[b, 0]), damped(f1, a, b_vel[b, 1]), damped(f2, a, b_vel[b, 2])
    t0, t1, t2 = damped(t0, a, b_omega[b, 0]), damped(t1, a, b_omega[b, 1]), damped(t2, a, b_omega[b, 2])
    b_force[b, 0], b_force[b, 1], b_force[b, 2] = f0, f1, f2
    b_torque[b, 0], b_torque[b, 1], b_torque[b, 2] = t0, t1, t2


@njit(cache=True)
def move_walls(W, t, dt):
    """Advance every wall by one step: servo or prescribed (ramped) translation, then rigid rotation."""
    origin, vel, mode = W.origin, W.vel, W.mode
    for w in range(origin.shape[0]):
        if mode[w] == 1:
            a0, a1, a2 = W.servo_axis[w, 0], W.servo_axis[w, 1], W.servo_axis[w, 2]
            # force the wall exerts on the particles along its push axis
            applied = -(W.force[w, 0] * a0 + W.force[w, 1] * a1 + W.force[w, 2] * a2)
            err = W.servo_target[w] - applied
            vmax = W.servo_vmax[w]
            # k_sum: what the wall's contacts add to its force per metre it moves within one step, the springs'
            # k plus the dashpots' c / dt. A move v dt is felt through both (the dashpots at once), so the step
            # closes servo_gain of the error whatever the damping. With springs alone in the denominator, a
            # dashpot ratio c / (k dt) above (2 / gain - 1) / 2 (49.5 at the lab's 0.02) made every step
            # overshoot: on Hertzian contacts at small forces (k ~ F^(1/3), Rayleigh's step fixed) the lid
            # chattered and stirred the packing (tests/engine/test_servo.py)
            if W.k_sum[w] > 0.0:
                speed = W.servo_gain[w] * err / (W.k_sum[w] * dt)
            else:
                speed = vmax if err > 0.0 else -vmax
            speed = min(max(speed, -vmax), vmax)
            vel[w, 0], vel[w, 1], vel[w, 2] = speed * a0, speed * a1, speed * a2
        else:
            f = 1.0
            if W.ramp_time[w] > 0.0:
                f = min(max((t - W.ramp_start[w]) / W.ramp_time[w], 0.0), 1.0)
            vel[w, 0] = f * W.vel_target[w, 0]
            vel[w, 1] = f * W.vel_target[w, 1]
            vel[w, 2] = f * W.vel_target[w, 2]
        for k in range(3):
            origin[w, k] += dt * vel[w, k]
            W.centre[w, k] += dt * vel[w, k]
        o0, o1, o2 = W.omega[w, 0], W.omega[w, 1], W.omega[w, 2]
        rate = math.sqrt(o0 * o0 + o1 * o1 + o2 * o2)
        if rate > 0.0:
            _rotate_wall(W, w, o0 / rate, o1 / rate, o2 / rate, rate * dt)
            W.swept[w] += rate * dt * W.reach[w]


@njit(cache=True)
def _rotate_wall(W, w, e0, e1, e2, angle):
    """Turn wall w by `angle` about the unit axis e through its rotation centre (Rodrigues' matrix)."""
    c, s = math.cos(angle), math.sin(angle)
    r = np.empty((3, 3))
    e = (e0, e1, e2)
    for i in range(3):
        for j in range(3):
            r[i, j] = (1.0 - c) * e[i] * e[j] + (c if i == j else 0.0)
    r[0, 1] -= s * e2
    r[0, 2] += s * e1
    r[1, 0] += s * e2
    r[1, 2] -= s * e0
    r[2, 0] -= s * e1
    r[2, 1] += s * e0
    _rotate_vec(r, W.origin[w], W.centre[w])
    zero = np.zeros(3)
    for row in range(3):
        _rotate_vec(r, W.frame[w, row], zero)
    for t in range(W.tri_start[w], W.tri_start[w + 1]):
        for v in range(3):
            _rotate_vec(r, W.tri[t, v], zero)


@njit(cache=True)
def _rotate_vec(r, x, about):
    d0, d1, d2 = x[0] - about[0], x[1] - about[1], x[2] - about[2]
    x[0] = about[0] + r[0, 0] * d0 + r[0, 1] * d1 + r[0, 2] * d2
    x[1] = about[1] + r[1, 0] * d0 + r[1, 1] * d1 + r[1, 2] * d2
    x[2] = about[2] + r[2, 0] * d0 + r[2, 1] * d1 + r[2, 2] * d2


@njit(cache=True)
def wall_resultants(n_walls, wc_wall, wc_force, wc_point, wc_k, origin, force, moment, k_sum):
    """Per-wall force by the particles on it, moment about its reference point, and what its contacts add to
    that force per metre the wall moves within one step (springs' k plus dashpots' c / dt, for the servo)."""
    force[:] = 0.0
    moment[:] = 0.0
    k_sum[:] = 0.0
    for e in range(wc_wall.shape[0]):
        w = wc_wall[e]
        if wc_k[e] == 0.0:
            continue
        f0, f1, f2 = wc_force[e, 0], wc_force[e, 1], wc_force[e, 2]
        r0 = wc_point[e, 0] - origin[w, 0]
        r1 = wc_point[e, 1] - origin[w, 1]
        r2 = wc_point[e, 2] - origin[w, 2]
        force[w, 0] += f0
        force[w, 1] += f1
        force[w, 2] += f2
        moment[w, 0] += r1 * f2 - r2 * f1
        moment[w, 1] += r2 * f0 - r0 * f2
        moment[w, 2] += r0 * f1 - r1 * f0
        k_sum[w] += wc_k[e]


@njit(cache=True)
def needs_rebuild(s_pos, pos_at_build, W, skin):
    """True when a sphere or a wall surface may have moved far enough to make the lists incomplete."""
    ds = 0.0
    for i in range(s_pos.shape[0]):
        ds = farther(ds, moved_sq(i, s_pos, pos_at_build))
    return lists_stale(ds, W, skin)


@njit(cache=True, inline='always')
def farther(largest, d):
    """max(largest, d) that keeps a nan: a non-finite position must reach the rebuild, whose
    finiteness check stops the run naming the body (with numpy's error model a coincident pair's
    division by zero is a nan, not an exception)."""
    if largest != largest:
        return largest
    return largest if largest >= d else d


@njit(cache=True, inline='always')
def moved_sq(i, s_pos, pos_at_build):
    """Squared displacement of sphere i since the last neighbour-list build."""
    d0 = s_pos[i, 0] - pos_at_build[i, 0]
    d1 = s_pos[i, 1] - pos_at_build[i, 1]
    d2 = s_pos[i, 2] - pos_at_build[i, 2]
    return d0 * d0 + d1 * d1 + d2 * d2


@njit(cache=True)
def lists_stale(ds, W, skin):
    """Rebuild test from the largest squared sphere displacement ds (the body pass tracks it per chunk
    as it drifts, so no serial pass over all spheres is needed each step) and the walls' motion."""
    dw = 0.0
    origin, at_build = W.origin, W.origin_at_build
    for w in range(origin.shape[0]):
        d0 = origin[w, 0] - at_build[w, 0]
        d1 = origin[w, 1] - at_build[w, 1]
        d2 = origin[w, 2] - at_build[w, 2]
        # a rotating wall's surface near the spheres moves at most |omega| dt x reach per step
        dw = max(dw, math.sqrt(d0 * d0 + d1 * d1 + d2 * d2) + W.swept[w])
    ds = math.sqrt(ds)
    # written so that a nan displacement counts as stale (see farther)
    return not (2.0 * ds <= skin and ds + dw <= skin)
