"""Neighbour lists against brute force, including rows wider than the first scan's buffer."""
import numpy as np

from engine import neighbors


def _brute(pos, rad, body, skin):
    d = np.linalg.norm(pos[:, None] - pos[None], axis=2)
    near = (d < rad[:, None] + rad[None] + skin) & (body[:, None] != body[None])
    return np.nonzero(np.triu(near, 1))


def test_pairs_match_brute_force_with_crowded_rows():
    rng = np.random.default_rng(0)
    n = 3000
    pos = rng.uniform(0.0, 0.1, (n, 3))
    rad = rng.uniform(0.002, 0.006, n)  # overlapping cloud: rows of up to ~40 partners
    body = np.arange(n) // 4  # four-sphere bodies: no pairs inside a body
    pi, pj, row_start = neighbors.build_pairs(pos, rad, body, 0.003)
    i_ref, j_ref = _brute(pos, rad, body, 0.003)
    assert np.diff(row_start).max() > 16  # the widened second scan is exercised
    assert np.array_equal(pi, i_ref) and np.array_equal(pj, j_ref)
    assert np.array_equal(row_start, np.concatenate([[0], np.cumsum(np.bincount(i_ref, minlength=n))]))


def test_history_is_carried_by_key():
    old_key = np.array([3, 7, 12, 40], np.int64)
    old_hist = np.arange(8, dtype=float).reshape(4, 2) + 1.0
    new_key = np.array([1, 7, 12, 13, 41], np.int64)
    out = neighbors.carry_history(old_key, old_hist, new_key, 2)
    assert np.array_equal(out, [[0, 0], [3, 4], [5, 6], [0, 0], [0, 0]])
