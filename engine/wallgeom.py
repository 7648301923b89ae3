"""Closest-point geometry of wall primitives (numba).

Every function returns (dist, n0, n1, n2, on_face): the distance of a sphere centre from the wall
surface along the unit normal n that points from the surface to the centre (negative inside a
solid box or behind a one-sided plane), and whether the closest point lies inside a face (used to
drop duplicate edge contacts on meshes). Local frames: rows of `frame[w]` are the axes u, v, w.
The distance functions take a wall's (or triangle's) row as tuples of floats, read by `wall_row` /
`triangle_row`: tuples are plain values to numba, while every array handed to an inlined function
with branches costs a reference-count increment and decrement per call, which cost more than the
geometry itself in the per-step wall pass.
"""
from __future__ import annotations

import math

from numba import njit

PLANE, DISK, RECTANGLE, FRUSTUM, BOX, MESH = 0, 1, 2, 3, 4, 5


@njit(cache=True, inline='always')
def wall_row(origin, frame, par, w):
    """Wall w's origin (3), frame rows u, v, w (9, row-major) and parameters (3), as float tuples."""
    return ((origin[w, 0], origin[w, 1], origin[w, 2]),
            (frame[w, 0, 0], frame[w, 0, 1], frame[w, 0, 2], frame[w, 1, 0], frame[w, 1, 1], frame[w, 1, 2],
             frame[w, 2, 0], frame[w, 2, 1], frame[w, 2, 2]),
            (par[w, 0], par[w, 1], par[w, 2]))


@njit(cache=True, inline='always')
def triangle_row(tri, t, origin, w):
    """Triangle t of mesh wall w: its vertices (3 x 3, relative to the wall origin) and the origin."""
    return ((tri[t, 0, 0], tri[t, 0, 1], tri[t, 0, 2], tri[t, 1, 0], tri[t, 1, 1], tri[t, 1, 2],
             tri[t, 2, 0], tri[t, 2, 1], tri[t, 2, 2]),
            (origin[w, 0], origin[w, 1], origin[w, 2]))


@njit(cache=True, inline='always')
def _to_local(fr, d0, d1, d2):
    return (
        fr[0] * d0 + fr[1] * d1 + fr[2] * d2,
        fr[3] * d0 + fr[4] * d1 + fr[5] * d2,
        fr[6] * d0 + fr[7] * d1 + fr[8] * d2,
    )


@njit(cache=True, inline='always')
def _to_world(fr, l0, l1, l2):
    return (
        fr[0] * l0 + fr[3] * l1 + fr[6] * l2,
        fr[1] * l0 + fr[4] * l1 + fr[7] * l2,
        fr[2] * l0 + fr[5] * l1 + fr[8] * l2,
    )


@njit(cache=True, inline='always')
def _from_local_diff(fr, l0, l1, l2, fallback_w):
    dist = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2)
    if dist > 0.0:
        n0, n1, n2 = _to_world(fr, l0 / dist, l1 / dist, l2 / dist)
    else:
        n0, n1, n2 = _to_world(fr, 0.0, 0.0, fallback_w)
    return dist, n0, n1, n2


@njit(cache=True, inline='always')
def primitive_distance(kind, row, x0, x1, x2):
    """Distance of the centre x from a primitive wall whose `wall_row` is row."""
    o, fr, par = row
    l0, l1, l2 = _to_local(fr, x0 - o[0], x1 - o[1], x2 - o[2])
    if kind == PLANE:
        return l2, fr[6], fr[7], fr[8], True
    if kind == DISK:
        rho = math.sqrt(l0 * l0 + l1 * l1)
        if rho <= par[0]:
            dist, n0, n1, n2 = _from_local_diff(fr, 0.0, 0.0, l2, 1.0)
            return dist, n0, n1, n2, True
        s = par[0] / rho
        dist, n0, n1, n2 = _from_local_diff(fr, l0 - s * l0, l1 - s * l1, l2, 1.0)
        return dist, n0, n1, n2, False
    if kind == RECTANGLE:
        c0 = min(max(l0, -par[0]), par[0])
        c1 = min(max(l1, -par[1]), par[1])
        dist, n0, n1, n2 = _from_local_diff(fr, l0 - c0, l1 - c1, l2, 1.0)
        return dist, n0, n1, n2, c0 == l0 and c1 == l1
    if kind == FRUSTUM:
        r0, r1, h = par[0], par[1], par[2]
        rho = math.sqrt(l0 * l0 + l1 * l1)
        if rho > 0.0:
            e0, e1 = l0 / rho, l1 / rho
        else:
            e0, e1 = 1.0, 0.0
        dr = r1 - r0
        t = ((rho - r0) * dr + l2 * h) / (dr * dr + h * h)
        on_face = t > 0.0 and t < 1.0
        t = min(max(t, 0.0), 1.0)
        dq = rho - (r0 + t * dr)
        dz = l2 - t * h
        # radial sign: the normal points to the side the centre is on (inside for a bucket)
        dist, n0, n1, n2 = _from_local_diff(fr, dq * e0, dq * e1, dz, 1.0)
        return dist, n0, n1, n2, on_face
    if kind == BOX:
        q0 = abs(l0) - par[0]
        q1 = abs(l1) - par[1]
        q2 = abs(l2) - par[2]
        if q0 > 0.0 or q1 > 0.0 or q2 > 0.0:
            c0 = min(max(l0, -par[0]), par[0])
            c1 = min(max(l1, -par[1]), par[1])
            c2 = min(max(l2, -par[2]), par[2])
            dist, n0, n1, n2 = _from_local_diff(fr, l0 - c0, l1 - c1, l2 - c2, 1.0)
            return dist, n0, n1, n2, True
        # centre inside the box: push out through the nearest face
        if q0 >= q1 and q0 >= q2:
            n0, n1, n2 = _to_world(fr, 1.0 if l0 >= 0 else -1.0, 0.0, 0.0)
            return q0, n0, n1, n2, True
        if q1 >= q2:
            n0, n1, n2 = _to_world(fr, 0.0, 1.0 if l1 >= 0 else -1.0, 0.0)
            return q1, n0, n1, n2, True
        n0, n1, n2 = _to_world(fr, 0.0, 0.0, 1.0 if l2 >= 0 else -1.0)
        return q2, n0, n1, n2, True
    return 1e300, 0.0, 0.0, 1.0, True


@njit(cache=True, inline='always')
def triangle_distance(row, x0, x1, x2):
    """Closest point on the triangle whose `triangle_row` is row (Ericson, Real-Time Collision Detection
    5.1.5)."""
    vt, o = row
    a0, a1, a2 = vt[0] + o[0], vt[1] + o[1], vt[2] + o[2]
    ab0, ab1, ab2 = vt[3] - vt[0], vt[4] - vt[1], vt[5] - vt[2]
    ac0, ac1, ac2 = vt[6] - vt[0], vt[7] - vt[1], vt[8] - vt[2]
    ap0, ap1, ap2 = x0 - a0, x1 - a1, x2 - a2
    d1 = ab0 * ap0 + ab1 * ap1 + ab2 * ap2
    d2 = ac0 * ap0 + ac1 * ap1 + ac2 * ap2
    face = False
    if d1 <= 0.0 and d2 <= 0.0:
        v, w = 0.0, 0.0
    else:
        bp0, bp1, bp2 = ap0 - ab0, ap1 - ab1, ap2 - ab2
        d3 = ab0 * bp0 + ab1 * bp1 + ab2 * bp2
        d4 = ac0 * bp0 + ac1 * bp1 + ac2 * bp2
        cp0, cp1, cp2 = ap0 - ac0, ap1 - ac1, ap2 - ac2
        d5 = ab0 * cp0 + ab1 * cp1 + ab2 * cp2
        d6 = ac0 * cp0 + ac1 * cp1 + ac2 * cp2
        vc = d1 * d4 - d3 * d2
        vb = d5 * d2 - d1 * d6
        va = d3 * d6 - d5 * d4
        if d3 >= 0.0 and d4 <= d3:
            v, w = 1.0, 0.0
        elif d6 >= 0.0 and d5 <= d6:
            v, w = 0.0, 1.0
        elif vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
            v, w = d1 / (d1 - d3), 0.0
        elif vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
            v, w = 0.0, d2 / (d2 - d6)
        elif va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
            w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
            v = 1.0 - w
        else:
            denom = 1.0 / (va + vb + vc)
            v, w = vb * denom, vc * denom
            face = True
    q0 = ap0 - v * ab0 - w * ac0
    q1 = ap1 - v * ab1 - w * ac1
    q2 = ap2 - v * ab2 - w * ac2
    dist = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2)
    if dist > 0.0:
        return dist, q0 / dist, q1 / dist, q2 / dist, face
    n0 = ab1 * ac2 - ab2 * ac1
    n1 = ab2 * ac0 - ab0 * ac2
    n2 = ab0 * ac1 - ab1 * ac0
    nn = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    return 0.0, n0 / nn, n1 / nn, n2 / nn, face
