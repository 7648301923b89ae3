"""Verlet neighbour lists from cell lists, and carrying contact history across rebuilds.

Pairs are stored once (i < j), sorted by (i, j), as CSR rows; every pass is two-phase (count,
prefix sum, fill) so parallel builds are deterministic. History is matched by the sorted key
i * n + j with a binary search, so it survives any rebuild; memory is linear in N.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .wallgeom import MESH, primitive_distance, triangle_distance, triangle_row, wall_row


@njit(cache=True)
def _grid(pos, radius, skin):
    n = pos.shape[0]
    lo = np.empty(3)
    hi = np.empty(3)
    for k in range(3):
        lo[k] = pos[:, k].min()
        hi[k] = pos[:, k].max()
    cell = 2.0 * radius.max() + skin
    # cap the cell count (a few escaped particles must not blow up memory)
    while True:
        dims = np.empty(3, np.int64)
        total = 1
        for k in range(3):
            dims[k] = int((hi[k] - lo[k]) / cell) + 1
            total *= dims[k]
        if total <= 4 * n + 64:
            break
        cell *= 1.26
    return lo, cell, dims


@njit(cache=True)
def _cell_sort(pos, lo, cell, dims):
    n = pos.shape[0]
    ncell = dims[0] * dims[1] * dims[2]
    cid = np.empty(n, np.int64)
    for i in range(n):
        c0 = min(int((pos[i, 0] - lo[0]) / cell), dims[0] - 1)
        c1 = min(int((pos[i, 1] - lo[1]) / cell), dims[1] - 1)
        c2 = min(int((pos[i, 2] - lo[2]) / cell), dims[2] - 1)
        cid[i] = (c2 * dims[1] + c1) * dims[0] + c0
    start = np.zeros(ncell + 1, np.int64)
    for i in range(n):
        start[cid[i] + 1] += 1
    for c in range(ncell):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, np.int64)
    for i in range(n):
        order[fill[cid[i]]] = i
        fill[cid[i]] += 1
    return cid, start, order


@njit(cache=True)
def _scan_row(i, x0, x1, x2, r_i, b_i, skin, lo, cell, dims, start, order, c_pos, c_rad, c_body, out, cap):
    """Neighbours j > i of sphere i within reach; writes the first `cap` into out, returns the count.

    c_* are the sphere data copied in cell order, so the inner loop reads memory sequentially.
    """
    c0 = min(int((x0 - lo[0]) / cell), dims[0] - 1)
    c1 = min(int((x1 - lo[1]) / cell), dims[1] - 1)
    c2 = min(int((x2 - lo[2]) / cell), dims[2] - 1)
    count = 0
    for z in range(max(c2 - 1, 0), min(c2 + 2, dims[2])):
        for y in range(max(c1 - 1, 0), min(c1 + 2, dims[1])):
            for x in range(max(c0 - 1, 0), min(c0 + 2, dims[0])):
                c = (z * dims[1] + y) * dims[0] + x
                for k in range(start[c], start[c + 1]):
                    j = order[k]
                    if j <= i or c_body[k] == b_i:
                        continue
                    d0 = c_pos[k, 0] - x0
                    d1 = c_pos[k, 1] - x1
                    d2 = c_pos[k, 2] - x2
                    reach = r_i + c_rad[k] + skin
                    if d0 * d0 + d1 * d1 + d2 * d2 < reach * reach:
                        if count < cap:
                            out[count] = j
                        count += 1
    return count


@njit(cache=True, parallel=True)
def _scan_all(pos, radius, body, skin, lo, cell, dims, start, order, c_pos, c_rad, c_body, buf, counts):
    cap = buf.shape[1]
    for i in prange(pos.shape[0]):
        counts[i] = _scan_row(i, pos[i, 0], pos[i, 1], pos[i, 2], radius[i], body[i], skin, lo, cell, dims,
                              start, order, c_pos, c_rad, c_body, buf[i], cap)


@njit(cache=True, parallel=True)
def _compact(buf, counts, row_start, pair_i, pair_j):
    for i in prange(counts.shape[0]):
        a = row_start[i]
        m = counts[i]
        for k in range(m):
            pair_j[a + k] = buf[i, k]
        pair_j[a:a + m].sort()
        for k in range(m):
            pair_i[a + k] = i


@njit(cache=True, parallel=True)
def build_pairs(pos, radius, body, skin):
    """Return (pair_i, pair_j, row_start) of all sphere pairs of different bodies within reach.

    One scan into fixed-width rows (widened and repeated only if a row overflows), then a compaction.
    The scan is a function of its own: a prange inside the retry loop, over a re-bound buffer, was
    mis-compiled by numba (rows landed in the wrong place once a row overflowed).
    """
    n = pos.shape[0]
    lo, cell, dims = _grid(pos, radius, skin)
    cid, start, order = _cell_sort(pos, lo, cell, dims)
    c_pos = np.empty((n, 3))
    c_rad = np.empty(n)
    c_body = np.empty(n, np.int64)
    for k in prange(n):
        j = order[k]
        c_pos[k, 0], c_pos[k, 1], c_pos[k, 2] = pos[j, 0], pos[j, 1], pos[j, 2]
        c_rad[k] = radius[j]
        c_body[k] = body[j]
    counts = np.zeros(n, np.int64)
    cap = 16
    buf = np.empty((n, cap), np.int32)  # a temporary at the rebuild's memory peak: half the bytes of int64
    _scan_all(pos, radius, body, skin, lo, cell, dims, start, order, c_pos, c_rad, c_body, buf, counts)
    widest = counts.max() if n else 0
    if widest > cap:
        buf = np.empty((n, widest), np.int32)
        _scan_all(pos, radius, body, skin, lo, cell, dims, start, order, c_pos, c_rad, c_body, buf, counts)
    row_start = np.zeros(n + 1, np.int64)
    for i in range(n):
        row_start[i + 1] = row_start[i] + counts[i]
    pair_j = np.empty(row_start[n], np.int64)
    pair_i = np.empty(row_start[n], np.int64)
    _compact(buf, counts, row_start, pair_i, pair_j)
    return pair_i, pair_j, row_start


@njit(cache=True)
def _wall_scan(i, pos, radius, skin, w_type, w_origin, w_frame, w_par, w_tri_start, tri, box_lo, box_hi,
               out_wall, out_tri, write):
    count = 0
    reach = radius[i] + skin
    x0, x1, x2 = pos[i, 0], pos[i, 1], pos[i, 2]
    for w in range(w_type.shape[0]):
        if w_type[w] == MESH:
            continue
        dist, n0, n1, n2, face = primitive_distance(w_type[w], wall_row(w_origin, w_frame, w_par, w), x0, x1, x2)
        if dist < reach:
            if write:
                out_wall[count] = w
                out_tri[count] = -1
            count += 1
    for w in range(w_type.shape[0]):
        if w_type[w] != MESH:
            continue
        if (x0 < box_lo[w, 0] + w_origin[w, 0] - reach or x0 > box_hi[w, 0] + w_origin[w, 0] + reach
                or x1 < box_lo[w, 1] + w_origin[w, 1] - reach or x1 > box_hi[w, 1] + w_origin[w, 1] + reach
                or x2 < box_lo[w, 2] + w_origin[w, 2] - reach or x2 > box_hi[w, 2] + w_origin[w, 2] + reach):
            continue
        for t in range(w_tri_start[w], w_tri_start[w + 1]):
            dist, n0, n1, n2, face = triangle_distance(triangle_row(tri, t, w_origin, w), x0, x1, x2)
            if dist < reach:
                if write:
                    out_wall[count] = w
                    out_tri[count] = t
                count += 1
    return count


@njit(cache=True, parallel=True)
def build_wall_list(pos, radius, skin, w_type, w_origin, w_frame, w_par, w_tri_start, tri, box_lo, box_hi):
    """Sphere-wall candidates as CSR rows per sphere: (start, wall, triangle or -1)."""
    n = pos.shape[0]
    counts = np.zeros(n, np.int64)
    d_w = np.empty(0, np.int64)
    d_t = np.empty(0, np.int64)
    for i in prange(n):
        counts[i] = _wall_scan(i, pos, radius, skin, w_type, w_origin, w_frame, w_par, w_tri_start, tri,
                               box_lo, box_hi, d_w, d_t, False)
    start = np.zeros(n + 1, np.int64)
    for i in range(n):
        start[i + 1] = start[i] + counts[i]
    wall = np.empty(start[n], np.int64)
    tri_idx = np.empty(start[n], np.int64)
    for i in prange(n):
        _wall_scan(i, pos, radius, skin, w_type, w_origin, w_frame, w_par, w_tri_start, tri, box_lo, box_hi,
                   wall[start[i]:start[i + 1]], tri_idx[start[i]:start[i + 1]], True)
    return start, wall, tri_idx


@njit(cache=True)
def carry_history(old_key, old_hist, new_key, n_hist):
    """History rows of new contacts looked up by key in the old keys; new contacts get 0.

    Both key arrays are ascending (rows sorted by sphere, then partner), so one merge pass does it.
    """
    out = np.zeros((new_key.shape[0], n_hist))
    m = old_key.shape[0]
    k = 0
    for p in range(new_key.shape[0]):
        key = new_key[p]
        while k < m and old_key[k] < key:
            k += 1
        if k == m:
            break
        if old_key[k] == key:
            for h in range(n_hist):
                out[p, h] = old_hist[k, h]
    return out


def pair_keys(pair_i: np.ndarray, pair_j: np.ndarray, n: int) -> np.ndarray:
    return pair_i.astype(np.int64) * np.int64(n) + pair_j


def wall_keys(row_start: np.ndarray, wall: np.ndarray, tri_idx: np.ndarray, n_walls: int,
              n_elements: int) -> np.ndarray:
    """Key sphere * E + element, element = wall for primitives, n_walls + triangle for meshes."""
    sphere = np.repeat(np.arange(row_start.shape[0] - 1, dtype=np.int64), np.diff(row_start))
    elem = np.where(tri_idx >= 0, n_walls + tri_idx, wall)
    return sphere * np.int64(n_elements) + elem


def max_sq(x: np.ndarray) -> float:
    return float(math.sqrt(max(0.0, float((x * x).sum(axis=1).max())))) if x.size else 0.0
