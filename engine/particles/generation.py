"""Packings: random non-overlapping insertion of clumps in a box or vertical cylinder, and lattices.

Random insertion follows PFC's ``generate``: each body gets a uniform random
position (and a uniform random orientation) and is kept only if none of its
spheres overlaps a sphere already placed and all of its spheres lie inside the
region; after ``max_attempts`` failures for one body the region is declared too
full. Overlap checks use a uniform cell grid (cell = largest sphere diameter)
in a numba kernel, so 10,000 spheres take well under a second once compiled.

Random numbers come from a numpy ``Generator`` in blocks handed to the kernel,
so a seed reproduces the packing bit for bit, whatever the block size.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numba
import numpy as np

from .templates import ClumpTemplate

# ----------------------------------------------------------------------------- regions


@dataclass(frozen=True)
class BoxRegion:
    lower_m: tuple[float, float, float]
    upper_m: tuple[float, float, float]

    def __post_init__(self):
        lo, hi = np.asarray(self.lower_m, float), np.asarray(self.upper_m, float)
        if lo.shape != (3,) or hi.shape != (3,) or not np.all(hi > lo):
            raise ValueError(f"box region needs lower_m < upper_m in x, y, z; got {self.lower_m}, {self.upper_m}")

    @property
    def volume_m3(self) -> float:
        return float(np.prod(np.subtract(self.upper_m, self.lower_m)))

    def bounds(self):
        return np.asarray(self.lower_m, float), np.asarray(self.upper_m, float)

    def _kernel_params(self):
        return 0, np.array([*self.lower_m, *self.upper_m], dtype=np.float64)


@dataclass(frozen=True)
class CylinderRegion:
    """Vertical (z-axis) cylinder, e.g. a container or the rainfall column above it."""

    radius_m: float
    z_min_m: float
    z_max_m: float
    centre_xy_m: tuple[float, float] = (0.0, 0.0)

    def __post_init__(self):
        if not self.radius_m > 0 or not self.z_max_m > self.z_min_m:
            raise ValueError(
                f"cylinder region needs radius_m > 0 and z_max_m > z_min_m; got radius_m={self.radius_m}, "
                f"z_min_m={self.z_min_m}, z_max_m={self.z_max_m}"
            )

    @property
    def volume_m3(self) -> float:
        return float(np.pi * self.radius_m**2 * (self.z_max_m - self.z_min_m))

    def bounds(self):
        cx, cy = self.centre_xy_m
        r = self.radius_m
        return np.array([cx - r, cy - r, self.z_min_m]), np.array([cx + r, cy + r, self.z_max_m])

    def _kernel_params(self):
        cx, cy = self.centre_xy_m
        return 1, np.array([cx, cy, self.radius_m, self.z_min_m, self.z_max_m, 0.0], dtype=np.float64)


Region = BoxRegion | CylinderRegion


class InsertionError(ValueError):
    """The region is too full to place the requested bodies."""


# ----------------------------------------------------------------------------- packing


def quaternion_to_matrix(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (w, x, y, z), body -> world."""
    q = np.asarray(q, dtype=np.float64)
    w, x, y, z = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    m = np.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0] = 1 - 2 * (y * y + z * z)
    m[..., 0, 1] = 2 * (x * y - w * z)
    m[..., 0, 2] = 2 * (x * z + w * y)
    m[..., 1, 0] = 2 * (x * y + w * z)
    m[..., 1, 1] = 1 - 2 * (x * x + z * z)
    m[..., 1, 2] = 2 * (y * z - w * x)
    m[..., 2, 0] = 2 * (x * z - w * y)
    m[..., 2, 1] = 2 * (y * z + w * x)
    m[..., 2, 2] = 1 - 2 * (x * x + y * y)
    return m


@dataclass
class Packing:
    """Bodies as template references, centre-of-mass positions and orientations (w, x, y, z), body -> world."""

    templates: list[ClumpTemplate]
    template_index: np.ndarray
    positions_m: np.ndarray
    orientations: np.ndarray
    meta: dict = field(default_factory=dict)

    def __post_init__(self):
        self.template_index = np.asarray(self.template_index, dtype=np.int64)
        self.positions_m = np.asarray(self.positions_m, dtype=np.float64).reshape(-1, 3)
        self.orientations = np.asarray(self.orientations, dtype=np.float64).reshape(-1, 4)
        n = len(self.template_index)
        if self.positions_m.shape[0] != n or self.orientations.shape[0] != n:
            raise ValueError("template_index, positions_m and orientations must have the same length")
        if n and (self.template_index.min() < 0 or self.template_index.max() >= len(self.templates)):
            raise ValueError("template_index refers to a template that does not exist")

    @property
    def n_bodies(self) -> int:
        return int(len(self.template_index))

    @property
    def solid_volume_m3(self) -> float:
        vols = np.array([t.volume_m3 for t in self.templates])
        return float(vols[self.template_index].sum()) if self.n_bodies else 0.0

    def mass_kg(self, density_kg_m3: float) -> float:
        return float(density_kg_m3) * self.solid_volume_m3

    def sphere_positions(self):
        """World sphere centres (M, 3), radii (M,) and the owning body id (M,)."""
        counts = np.array([t.n_spheres for t in self.templates], dtype=np.int64)[self.template_index]
        body = np.repeat(np.arange(self.n_bodies), counts)
        offsets = np.concatenate([self.templates[k].sphere_offsets_m for k in self.template_index]) if self.n_bodies else np.zeros((0, 3))
        radii = np.concatenate([self.templates[k].sphere_radii_m for k in self.template_index]) if self.n_bodies else np.zeros(0)
        rot = quaternion_to_matrix(self.orientations)[body]
        centres = self.positions_m[body] + np.einsum("mij,mj->mi", rot, offsets)
        return centres, radii, body


# ----------------------------------------------------------------------------- kernel


@numba.njit(cache=True)
def _inside(kind, prm, x, y, z, r):
    if kind == 0:
        return (x - r >= prm[0] and x + r <= prm[3] and y - r >= prm[1] and y + r <= prm[4]
                and z - r >= prm[2] and z + r <= prm[5])
    dx = x - prm[0]
    dy = y - prm[1]
    rr = prm[2] - r
    return rr >= 0.0 and dx * dx + dy * dy <= rr * rr and z - r >= prm[3] and z + r <= prm[4]


@numba.njit(cache=True)
def _insert_kernel(offsets, radii, t_start, t_count, t_rmin, body_template, order, rand, kind, prm,
                   lo, cell, dims, head, nxt, sc, sr, pos, quat, state, max_attempts, gap):
    """Place bodies order[state[0]:] using the uniforms in ``rand``; state = [body, attempts, spheres, status]."""
    k, att, m = state[0], state[1], state[2]
    nb = order.shape[0]
    used = 0
    wc = np.empty((16, 3))
    while k < nb:
        if used >= rand.shape[0]:
            state[0], state[1], state[2], state[3] = k, att, m, 0
            return
        u = rand[used]
        used += 1
        b = order[k]
        t = body_template[b]
        rmin = t_rmin[t]
        # position: uniform in the region shrunk by the smallest sphere radius
        if kind == 0:
            px = prm[0] + rmin + u[0] * (prm[3] - prm[0] - 2 * rmin)
            py = prm[1] + rmin + u[1] * (prm[4] - prm[1] - 2 * rmin)
            pz = prm[2] + rmin + u[2] * (prm[5] - prm[2] - 2 * rmin)
        else:
            rad = (prm[2] - rmin) * np.sqrt(u[0])
            th = 2.0 * np.pi * u[1]
            px = prm[0] + rad * np.cos(th)
            py = prm[1] + rad * np.sin(th)
            pz = prm[3] + rmin + u[2] * (prm[4] - prm[3] - 2 * rmin)
        # uniform random rotation (Shoemake)
        s1 = np.sqrt(1.0 - u[3])
        s2 = np.sqrt(u[3])
        qx = s1 * np.sin(2 * np.pi * u[4])
        qy = s1 * np.cos(2 * np.pi * u[4])
        qz = s2 * np.sin(2 * np.pi * u[5])
        qw = s2 * np.cos(2 * np.pi * u[5])
        n = t_count[t]
        if n > wc.shape[0]:
            wc = np.empty((n, 3))
        ok = True
        for i in range(n):
            j = t_start[t] + i
            ox, oy, oz = offsets[j, 0], offsets[j, 1], offsets[j, 2]
            # v' = v + 2 w (q x v) + 2 q x (q x v)
            cx = qy * oz - qz * oy
            cy = qz * ox - qx * oz
            cz = qx * oy - qy * ox
            x = px + ox + 2 * (qw * cx + qy * cz - qz * cy)
            y = py + oy + 2 * (qw * cy + qz * cx - qx * cz)
            z = pz + oz + 2 * (qw * cz + qx * cy - qy * cx)
            wc[i, 0], wc[i, 1], wc[i, 2] = x, y, z
            r = radii[j]
            if not _inside(kind, prm, x, y, z, r):
                ok = False
                break
            ix = int((x - lo[0]) / cell)
            iy = int((y - lo[1]) / cell)
            iz = int((z - lo[2]) / cell)
            for ax in range(max(ix - 1, 0), min(ix + 2, dims[0])):
                for ay in range(max(iy - 1, 0), min(iy + 2, dims[1])):
                    for az in range(max(iz - 1, 0), min(iz + 2, dims[2])):
                        p = head[(ax * dims[1] + ay) * dims[2] + az]
                        while p >= 0:
                            ddx = sc[p, 0] - x
                            ddy = sc[p, 1] - y
                            ddz = sc[p, 2] - z
                            lim = sr[p] + r + gap
                            if ddx * ddx + ddy * ddy + ddz * ddz < lim * lim:
                                ok = False
                                break
                            p = nxt[p]
                        if not ok:
                            break
                    if not ok:
                        break
                if not ok:
                    break
            if not ok:
                break
        if not ok:
            att += 1
            if att >= max_attempts:
                state[0], state[1], state[2], state[3] = k, att, m, -1
                return
            continue
        for i in range(n):
            j = t_start[t] + i
            sc[m, 0], sc[m, 1], sc[m, 2] = wc[i, 0], wc[i, 1], wc[i, 2]
            sr[m] = radii[j]
            c = (int((wc[i, 0] - lo[0]) / cell) * dims[1] + int((wc[i, 1] - lo[1]) / cell)) * dims[2] + int(
                (wc[i, 2] - lo[2]) / cell)
            nxt[m] = head[c]
            head[c] = m
            m += 1
        pos[b, 0], pos[b, 1], pos[b, 2] = px, py, pz
        quat[b, 0], quat[b, 1], quat[b, 2], quat[b, 3] = qw, qx, qy, qz
        k += 1
        att = 0
    state[0], state[1], state[2], state[3] = k, att, m, 1


def _flatten(templates):
    counts = np.array([t.n_spheres for t in templates], dtype=np.int64)
    start = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    offsets = np.ascontiguousarray(np.concatenate([t.sphere_offsets_m for t in templates]))
    radii = np.ascontiguousarray(np.concatenate([t.sphere_radii_m for t in templates]))
    rmin = np.array([t.sphere_radii_m.min() for t in templates])
    return offsets, radii, start, counts, rmin


def insert_random(templates, template_index, region: Region, seed=None, max_attempts: int = 5000,
                  min_gap_m: float = 0.0, block: int = 65536) -> Packing:
    """Insert one body per entry of ``template_index`` at random, without overlaps, inside ``region``.

    Bodies are placed largest first (the usual way to reach high fill
    fractions); the returned arrays keep the order of ``template_index``.
    ``seed`` is an int or a numpy Generator.
    """
    templates = list(templates)
    if not templates:
        raise ValueError("at least one template is needed")
    body_template = np.asarray(template_index, dtype=np.int64).ravel()
    if body_template.size and (body_template.min() < 0 or body_template.max() >= len(templates)):
        raise ValueError("template_index refers to a template that does not exist")
    if max_attempts < 1:
        raise ValueError("max_attempts must be >= 1")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    offsets, radii, start, counts, rmin = _flatten(templates)
    kind, prm = region._kernel_params()
    lo, hi = region.bounds()
    r_max = float(radii.max())
    cell = 2.0 * r_max + max(min_gap_m, 0.0)
    ext = hi - lo
    while np.prod(np.ceil(ext / cell)) > 2e7:  # keep the grid's memory bounded for very large regions
        cell *= 1.5
    dims = np.maximum(np.ceil(ext / cell), 1).astype(np.int64)
    n_sph = int(counts[body_template].sum())
    head = np.full(int(np.prod(dims)), -1, dtype=np.int64)
    nxt = np.full(n_sph, -1, dtype=np.int64)
    sc = np.zeros((n_sph, 3))
    sr = np.zeros(n_sph)
    nb = len(body_template)
    pos = np.zeros((nb, 3))
    quat = np.zeros((nb, 4))
    bounding = np.array([t.bounding_radius_m for t in templates])[body_template]
    order = np.argsort(-bounding, kind="stable").astype(np.int64)
    state = np.zeros(4, dtype=np.int64)
    while True:
        rand = rng.random((block, 6))
        _insert_kernel(offsets, radii, start, counts, rmin, body_template, order, rand, kind, prm, lo, cell,
                       dims, head, nxt, sc, sr, pos, quat, state, int(max_attempts), float(min_gap_m))
        if state[3] == 1:
            break
        if state[3] == -1:
            placed = int(state[0])
            vol = sum(templates[body_template[order[i]]].volume_m3 for i in range(placed))
            raise InsertionError(
                f"region too full: placed {placed} of {nb} bodies (solid fraction {vol / region.volume_m3:.3f} of "
                f"the region) before one failed {max_attempts} random placements; enlarge the region "
                f"(e.g. a taller rainfall column) or insert fewer bodies"
            )
    return Packing(templates=templates, template_index=body_template, positions_m=pos, orientations=quat,
                   meta={"region": region, "method": "random"})


def lattice(template: ClumpTemplate, region: Region, count: int | None = None, spacing_m: float | None = None,
            seed=None) -> Packing:
    """Copies of one template on a simple cubic lattice filling the region from the bottom (z) up.

    Spacing defaults to the template's bounding diameter, so bodies touch at
    most. Orientation is the identity unless ``seed`` is given (then random:
    still non-overlapping since the spacing covers the bounding sphere).
    """
    rb = template.bounding_radius_m
    a = float(spacing_m) if spacing_m is not None else 2.0 * rb
    if a < 2.0 * rb * (1 - 1e-12):
        raise ValueError(f"spacing_m={a} is below the template's bounding diameter {2 * rb}; bodies would overlap")
    lo, hi = region.bounds()
    axes = [np.arange(lo[i] + rb, hi[i] - rb + 1e-12, a) for i in range(3)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    pts = np.c_[x.ravel(), y.ravel(), z.ravel()]
    kind, prm = region._kernel_params()
    keep = np.array([_inside(kind, prm, p[0], p[1], p[2], rb) for p in pts], dtype=bool) if len(pts) else np.zeros(0, bool)
    pts = pts[keep]
    if count is not None:
        if count > len(pts):
            raise InsertionError(f"lattice holds {len(pts)} bodies in this region, {count} requested")
        pts = pts[:count]
    n = len(pts)
    if seed is None:
        quat = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    else:
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
        quat = rng.normal(size=(n, 4))
        quat /= np.linalg.norm(quat, axis=1, keepdims=True)
    return Packing(templates=[template], template_index=np.zeros(n, np.int64), positions_m=pts, orientations=quat,
                   meta={"region": region, "method": "lattice", "spacing_m": a})


def generate(mix, region: Region, seed=None, count: int | None = None, solid_volume_m3: float | None = None,
             **insert_options) -> Packing:
    """Sample bodies from a ``distributions.ShapeMix`` and insert them at random in ``region``.

    One Generator drives both the sizes/shapes and the placement, so ``seed``
    alone reproduces the packing. ``meta['component_index']`` tells each body's shape component.
    """
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    templates, component = mix.sample(rng, count=count, solid_volume_m3=solid_volume_m3)
    if not templates:
        raise ValueError("the shape mix produced no bodies (count 0?)")
    packing = insert_random(templates, np.arange(len(templates)), region, seed=rng, **insert_options)
    packing.meta["component_index"] = component
    return packing
