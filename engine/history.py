"""Contact history waiting for the next neighbour rebuild.

Adding or removing bodies or walls renumbers spheres, walls and mesh triangles. The tangential
springs (and effect slots) of the contacts that survive must follow them, or a packing under load
would lose its friction state whenever a lid is added or a shear box half is taken away. History is
kept here decoded (sphere / partner ids in the current numbering), re-indexed on every change, and
only turned into lookup keys when the rebuild needs them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import neighbors

_FIELDS = ("pair_i", "pair_j", "pair_hist", "wall_sphere", "wall_wall", "wall_tri", "wall_hist")


@dataclass
class PendingHistory:
    pair_i: np.ndarray
    pair_j: np.ndarray
    pair_hist: np.ndarray
    wall_sphere: np.ndarray
    wall_wall: np.ndarray
    wall_tri: np.ndarray  # -1 for primitive walls
    wall_hist: np.ndarray

    @classmethod
    def from_lists(cls, pairs, wall_contacts) -> "PendingHistory":
        """The lists' history by reference, not copied (tens of MB per rebuild at 200,000 spheres):
        every caller consumes it, or remaps it into new arrays, before the kernels touch the lists
        again."""
        wc = wall_contacts
        sphere = np.repeat(np.arange(wc.start.shape[0] - 1, dtype=np.int64), np.diff(wc.start))
        return cls(pairs.i, pairs.j, pairs.hist, sphere, wc.wall, wc.tri, wc.hist)

    def remapped(self, sphere_remap: np.ndarray, wall_remap: np.ndarray | None = None,
                 tri_remap: np.ndarray | None = None) -> "PendingHistory":
        """Follow a renumbering; entries mapped to -1 (deleted spheres, walls, triangles) are dropped."""
        pi, pj = sphere_remap[self.pair_i], sphere_remap[self.pair_j]
        ok = (pi >= 0) & (pj >= 0)
        # pairs are stored with i < j; where a renumbering swaps the two, the relative quantities in the
        # history (spring of i against j, rolling spring) change sign (see engine/effects/base.py)
        swap = pi > pj
        pi, pj = np.where(swap, pj, pi), np.where(swap, pi, pj)
        pair_hist = np.where(swap[:, None], -self.pair_hist, self.pair_hist)
        ws = sphere_remap[self.wall_sphere]
        ww = self.wall_wall if wall_remap is None else wall_remap[self.wall_wall]
        wt = self.wall_tri
        if tri_remap is not None and tri_remap.size:
            wt = np.where(wt >= 0, tri_remap[np.maximum(wt, 0)], -1)
        keep_w = (ws >= 0) & (ww >= 0) & ((self.wall_tri < 0) | (wt >= 0))
        return PendingHistory(pi[ok], pj[ok], pair_hist[ok], ws[keep_w], ww[keep_w], wt[keep_w],
                              self.wall_hist[keep_w])

    def pair_lookup(self, n_spheres: int) -> tuple[np.ndarray, np.ndarray]:
        """Ascending keys (as neighbors.carry_history needs) and their history rows."""
        return _sorted(neighbors.pair_keys(self.pair_i, self.pair_j, n_spheres), self.pair_hist)

    def wall_lookup(self, n_walls: int, n_elements: int) -> tuple[np.ndarray, np.ndarray]:
        elem = np.where(self.wall_tri >= 0, n_walls + self.wall_tri, self.wall_wall)
        return _sorted(self.wall_sphere * np.int64(n_elements) + elem, self.wall_hist)

    def to_arrays(self, prefix: str) -> dict[str, np.ndarray]:
        return {prefix + f: np.array(getattr(self, f), copy=True) for f in _FIELDS}

    @classmethod
    def from_arrays(cls, state: dict, prefix: str) -> "PendingHistory | None":
        if prefix + _FIELDS[0] not in state:
            return None
        return cls(*[np.array(state[prefix + f], copy=True) for f in _FIELDS])


def _sorted(keys: np.ndarray, hist: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    if keys.size > 1 and not np.all(keys[1:] > keys[:-1]):
        order = np.argsort(keys, kind="stable")
        keys, hist = keys[order], hist[order]
    return keys, hist
