"""Internal body numbering in space-filling order, hidden behind stable public ids.

Particles are inserted in random order, so neighbours in space sit far apart in memory; the pair
pass then reads partner data from all over the arrays and, on two threads, both cores miss cache
together (measured: 5,000 dense spheres, 2 threads, 4.8e6 particle-steps/s cell-ordered against
3.4e6 shuffled). The Simulation renumbers bodies (and their spheres) in cell order at some
rebuilds; users keep the ids they were given, translated by the maps built here.
"""
from __future__ import annotations

import numpy as np

from .state import Bodies, Spheres


def cell_order(pos: np.ndarray, cell_m: float) -> np.ndarray:
    """Permutation of the rows of pos sorted by (z, y, x) cell of size cell_m (stable)."""
    if pos.shape[0] < 2:
        return np.arange(pos.shape[0], dtype=np.int64)
    idx = np.floor((pos - pos.min(axis=0)) / cell_m).astype(np.int64)
    dims = idx.max(axis=0) + 1
    key = (idx[:, 2] * dims[1] + idx[:, 1]) * dims[0] + idx[:, 0]
    return np.argsort(key, kind="stable").astype(np.int64)


def sphere_rows(sphere_start: np.ndarray, body_order: np.ndarray) -> np.ndarray:
    """Sphere indices of the bodies in body_order, each body's spheres in their stored order."""
    counts = np.diff(sphere_start)[body_order]
    first = np.repeat(sphere_start[:-1][body_order], counts)
    within = np.arange(int(counts.sum()), dtype=np.int64) - np.repeat(np.cumsum(counts) - counts, counts)
    return (first + within).astype(np.int64)


def permute(bodies: Bodies, spheres: Spheres, order: np.ndarray) -> tuple[Bodies, Spheres, np.ndarray]:
    """Bodies (and spheres) renumbered so that new body k is old body order[k].

    Returns the new containers and the sphere remap old index -> new index (for contact history).
    """
    rows = sphere_rows(bodies.sphere_start, order)
    counts = np.diff(bodies.sphere_start)[order]
    new_body = np.empty_like(order)
    new_body[order] = np.arange(order.size, dtype=np.int64)
    fields = {f: getattr(bodies, f)[order] for f in Bodies._fields if f != "sphere_start"}
    fields["sphere_start"] = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    new_bodies = Bodies(**fields)
    new_spheres = Spheres(*[a[rows] for a in spheres])
    new_spheres = new_spheres._replace(body=new_body[new_spheres.body].astype(np.int64))
    remap = np.empty(rows.size, np.int64)
    remap[rows] = np.arange(rows.size, dtype=np.int64)
    return new_bodies, new_spheres, remap
