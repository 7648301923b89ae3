"""Rigid multi-sphere clump templates with overlap-corrected mass properties.

A template is the shape of one body in its principal frame: sphere centres
(centre of mass at the origin), radii, solid volume and principal moments of
inertia per unit density. The engine multiplies by the material density, so a
template is reused across densities and calibration runs.

Mass properties are those of the *union* of the spheres (PFC counts the lens of
an overlapping double clump once, thesis Eq. 4.9-4.10). Two routes:

* exact: when no three spheres overlap pairwise, the union is the sum of the
  spheres minus the pairwise lenses (inclusion-exclusion stops at pairs). Each
  lens is a solid of revolution whose slice area is a quadratic in the axial
  coordinate, so its volume, first and second moments are integrated exactly
  by 5-point Gauss-Legendre quadrature (exact up to degree 9; the integrands are
  at most degree 4);
* numerical: otherwise, a column integration. On an n x n grid of (x, y)
  columns the union of the sphere chords along z is merged exactly and the
  moments along z are integrated analytically; the (x, y) plane uses the
  midpoint rule, refined (n doubled) until the volume and inertia change by
  less than ``rel_tol`` (default 2e-4) between two refinements. Against the
  exact route this gives relative errors of order 1e-4 (tests/particles).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)


@dataclass(frozen=True, eq=False)
class ClumpTemplate:
    """One rigid body shape: spheres in the principal body frame, CoM at origin."""

    name: str
    sphere_offsets_m: np.ndarray
    sphere_radii_m: np.ndarray
    volume_m3: float
    principal_inertia_per_density_m5: np.ndarray

    def mass_kg(self, density_kg_m3: float) -> float:
        return float(density_kg_m3) * self.volume_m3

    def principal_inertia_kg_m2(self, density_kg_m3: float) -> np.ndarray:
        return float(density_kg_m3) * self.principal_inertia_per_density_m5

    @property
    def n_spheres(self) -> int:
        return int(self.sphere_radii_m.shape[0])

    @property
    def bounding_radius_m(self) -> float:
        """Radius of the smallest origin-centred sphere enclosing the body (insertion, neighbour cells)."""
        return float(np.max(np.linalg.norm(self.sphere_offsets_m, axis=1) + self.sphere_radii_m))

    @property
    def equivalent_radius_m(self) -> float:
        """Radius of the sphere with the same solid volume."""
        return float((3.0 * self.volume_m3 / (4.0 * np.pi)) ** (1.0 / 3.0))

    def scaled(self, factor: float) -> "ClumpTemplate":
        """Geometrically similar template: lengths x f, volume x f^3, inertia x f^5."""
        f = float(factor)
        if not f > 0:
            raise ValueError(f"scale factor must be > 0, got {factor}")
        return ClumpTemplate(
            name=self.name,
            sphere_offsets_m=_frozen(self.sphere_offsets_m * f),
            sphere_radii_m=_frozen(self.sphere_radii_m * f),
            volume_m3=self.volume_m3 * f**3,
            principal_inertia_per_density_m5=_frozen(self.principal_inertia_per_density_m5 * f**5),
        )


def _frozen(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


# --------------------------------------------------------------------------- exact pieces


def lens_volume_m3(r1_m: float, r2_m: float, distance_m: float) -> float:
    """Overlap volume of two spheres, thesis Eq. 4.9 (zero when apart, the small sphere when nested)."""
    r1, r2, d = float(r1_m), float(r2_m), float(distance_m)
    if d >= r1 + r2:
        return 0.0
    if d <= abs(r1 - r2):
        return 4.0 / 3.0 * np.pi * min(r1, r2) ** 3
    return (np.pi / (12.0 * d)) * (r1 + r2 - d) ** 2 * (
        d * d + 2 * d * r2 - 3 * r2 * r2 + 2 * d * r1 + 6 * r2 * r1 - 3 * r1 * r1
    )


def _revolution_moments(segments):
    """Volume, first and second axial moments and transverse second moment of a solid of revolution.

    ``segments``: (a, b, centre, radius) pieces where the slice at axial x is a
    disk of radius sqrt(radius^2 - (x - centre)^2). Returns (V, int x dV,
    int x^2 dV, int y^2 dV) with y one transverse direction.
    """
    v = m1 = m2 = t = 0.0
    for a, b, c, r in segments:
        if b <= a:
            continue
        x = 0.5 * (b - a) * _GL_X + 0.5 * (a + b)
        w = 0.5 * (b - a) * _GL_W
        rho2 = np.maximum(r * r - (x - c) ** 2, 0.0)
        area = np.pi * rho2
        v += float(np.sum(w * area))
        m1 += float(np.sum(w * area * x))
        m2 += float(np.sum(w * area * x * x))
        t += float(np.sum(w * np.pi * rho2 * rho2 / 4.0))
    return v, m1, m2, t


def _lens_segments(r1, r2, d):
    """Lens of sphere 1 (at 0) and sphere 2 (at d on the axis) as revolution segments."""
    if d >= r1 + r2:
        return []
    if d <= abs(r1 - r2):  # nested: the lens is the smaller sphere
        return [(-r1, r1, 0.0, r1)] if r1 <= r2 else [(d - r2, d + r2, d, r2)]
    x0 = (d * d + r1 * r1 - r2 * r2) / (2.0 * d)  # plane of the intersection circle
    return [(d - r2, x0, d, r2), (x0, r1, 0.0, r1)]


def _sphere_moments(c, r):
    """(V, first moment vector, second-moment tensor int r r^T dV) of a solid sphere about the origin."""
    v = 4.0 / 3.0 * np.pi * r**3
    s = (4.0 * np.pi * r**5 / 15.0) * np.eye(3) + v * np.outer(c, c)
    return v, v * c, s


def _lens_moments(c1, r1, c2, r2):
    axis = c2 - c1
    d = float(np.linalg.norm(axis))
    if d == 0.0:
        return _sphere_moments(c1, min(r1, r2))
    u = axis / d
    v, a1, a2, t = _revolution_moments(_lens_segments(r1, r2, d))
    s_local = a2 * np.outer(u, u) + t * (np.eye(3) - np.outer(u, u))
    first = a1 * u
    s = s_local + np.outer(c1, first) + np.outer(first, c1) + v * np.outer(c1, c1)
    return v, first + v * c1, s


def _overlapping_pairs(centres, radii):
    """Pairs that overlap by more than round-off (touching spheres, e.g. the pyramid, do not count)."""
    n = len(radii)
    pairs = []
    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(centres[j] - centres[i]) < (radii[i] + radii[j]) * (1.0 - 1e-9):
                pairs.append((i, j))
    return pairs


def _has_triple_overlap(n, pairs):
    linked = {p for p in pairs}
    for i, j in pairs:
        for k in range(j + 1, n):
            if (i, k) in linked and (j, k) in linked:
                return True
    return False


def _moments_exact(centres, radii, pairs):
    v = 0.0
    first = np.zeros(3)
    s = np.zeros((3, 3))
    for c, r in zip(centres, radii):
        dv, df, ds = _sphere_moments(c, r)
        v, first, s = v + dv, first + df, s + ds
    for i, j in pairs:
        dv, df, ds = _lens_moments(centres[i], radii[i], centres[j], radii[j])
        v, first, s = v - dv, first - df, s - ds
    return v, first, s


def _moments_columns(centres, radii, n, chunk_cells: int = 4_000_000):
    """Column integration of the union on an n x n grid (see module docstring).

    Columns are processed in chunks of about ``chunk_cells`` column-sphere entries so that memory
    stays bounded for clumps of many spheres.
    """
    lo = (centres - radii[:, None]).min(axis=0)
    hi = (centres + radii[:, None]).max(axis=0)
    hx, hy = (hi[0] - lo[0]) / n, (hi[1] - lo[1]) / n
    xs = lo[0] + hx * (np.arange(n) + 0.5)
    ys = lo[1] + hy * (np.arange(n) + 0.5)
    acc = np.zeros(10)  # V, Mx, My, Mz, Sxx, Syy, Szz, Sxy, Sxz, Syz (without the cell weight)
    rows = max(1, chunk_cells // (n * len(radii)))
    for i0 in range(0, n, rows):
        x, y = (a.ravel() for a in np.meshgrid(xs[i0:i0 + rows], ys, indexing="ij"))
        l0, l1, l2 = _column_union(x, y, centres, radii, lo[2])
        acc += np.array([
            l0.sum(), (x * l0).sum(), (y * l0).sum(), l1.sum(),
            # x^2 over a cell is xc^2 + h^2/12 (exact for the midpoint cell), likewise y^2
            ((x * x + hx * hx / 12.0) * l0).sum(), ((y * y + hy * hy / 12.0) * l0).sum(), l2.sum(),
            (x * y * l0).sum(), (x * l1).sum(), (y * l1).sum(),
        ])
    w = hx * hy
    v = w * acc[0]
    first = w * acc[1:4]
    s = w * np.array([[acc[4], acc[7], acc[8]], [acc[7], acc[5], acc[9]], [acc[8], acc[9], acc[6]]])
    return v, first, s


def _column_union(x, y, centres, radii, z_floor):
    """Integrals of 1, z, z^2 over the union of the sphere chords of each (x, y) column."""
    dx = x[:, None] - centres[None, :, 0]
    dy = y[:, None] - centres[None, :, 1]
    h2 = radii[None, :] ** 2 - dx * dx - dy * dy
    hit = h2 > 0.0
    h = np.sqrt(np.where(hit, h2, 0.0))
    zlo = np.where(hit, centres[None, :, 2] - h, z_floor)
    zhi = np.where(hit, centres[None, :, 2] + h, z_floor)
    order = np.argsort(zlo, axis=1)
    zlo = np.take_along_axis(zlo, order, axis=1)
    zhi = np.take_along_axis(zhi, order, axis=1)
    l0 = np.zeros(len(x))
    l1 = np.zeros(len(x))
    l2 = np.zeros(len(x))
    reach = np.full(len(x), z_floor)
    for k in range(len(radii)):  # sweep sorted intervals, counting each z once
        a = np.maximum(zlo[:, k], reach)
        b = np.maximum(zhi[:, k], a)
        l0 += b - a
        l1 += (b * b - a * a) / 2.0
        l2 += (b**3 - a**3) / 3.0
        reach = np.maximum(reach, zhi[:, k])
    return l0, l1, l2


def _inertia_about_com(v, first, s):
    com = first / v
    s_com = s - v * np.outer(com, com)
    return com, np.trace(s_com) * np.eye(3) - s_com


def union_mass_properties(centres_m, radii_m, rel_tol: float = 2e-4, max_grid: int = 1024):
    """(volume, centre of mass, inertia tensor per density about the CoM, method) of a sphere union."""
    centres = np.asarray(centres_m, dtype=np.float64).reshape(-1, 3)
    radii = np.asarray(radii_m, dtype=np.float64).ravel()
    pairs = _overlapping_pairs(centres, radii)
    if not _has_triple_overlap(len(radii), pairs):
        v, first, s = _moments_exact(centres, radii, pairs)
        com, inertia = _inertia_about_com(v, first, s)
        return v, com, inertia, "exact"
    # shift to the centroid of the sphere centres first so that s is well conditioned
    origin = centres.mean(axis=0)
    n = 128
    prev = None
    while True:
        v, first, s = _moments_columns(centres - origin, radii, n)
        com, inertia = _inertia_about_com(v, first, s)
        if prev is not None:
            dv = abs(v - prev[0]) / v
            di = np.max(np.abs(inertia - prev[1])) / np.max(np.abs(inertia))
            if max(dv, di) < rel_tol or 2 * n > max_grid:
                return v, com + origin, inertia, f"columns n={n}"
        prev = (v, inertia)
        n *= 2


def _principal_frame(inertia):
    """Eigen-decomposition with a deterministic, right-handed axis choice."""
    vals, vecs = np.linalg.eigh(inertia)
    scale = max(abs(vals).max(), 1e-300)
    if np.ptp(vals) <= 1e-10 * scale:  # isotropic: keep the input axes
        return np.full(3, vals.mean()), np.eye(3)
    for k in range(3):
        if vecs[np.argmax(np.abs(vecs[:, k])), k] < 0:
            vecs[:, k] = -vecs[:, k]
    if np.linalg.det(vecs) < 0:
        vecs[:, 2] = -vecs[:, 2]
    return vals, vecs


# --------------------------------------------------------------------------- factories


def from_spheres(centres_m, radii_m, name: str = "clump") -> ClumpTemplate:
    """Template from any sphere set (input frame arbitrary; moved to the principal frame)."""
    centres = np.asarray(centres_m, dtype=np.float64)
    radii = np.asarray(radii_m, dtype=np.float64)
    if centres.ndim != 2 or centres.shape[1] != 3 or centres.shape[0] < 1:
        raise ValueError(f"centres_m must have shape (n, 3) with n >= 1, got {centres.shape}")
    if radii.shape != (centres.shape[0],):
        raise ValueError(f"radii_m must have shape ({centres.shape[0]},), got {radii.shape}")
    if not np.all(np.isfinite(centres)) or not np.all(np.isfinite(radii)):
        raise ValueError("centres_m and radii_m must be finite")
    if np.any(radii <= 0):
        raise ValueError(f"every sphere radius must be > 0, got min {radii.min()}")
    v, com, inertia, _ = union_mass_properties(centres, radii)
    vals, axes = _principal_frame(inertia)
    offsets = (centres - com) @ axes
    return ClumpTemplate(
        name=name,
        sphere_offsets_m=_frozen(offsets),
        sphere_radii_m=_frozen(radii),
        volume_m3=float(v),
        principal_inertia_per_density_m5=_frozen(vals),
    )


def sphere(radius_m: float) -> ClumpTemplate:
    r = float(radius_m)
    if not r > 0:
        raise ValueError(f"radius_m must be > 0, got {radius_m}")
    v = 4.0 / 3.0 * np.pi * r**3
    return ClumpTemplate(
        name="sphere",
        sphere_offsets_m=_frozen(np.zeros((1, 3))),
        sphere_radii_m=_frozen([r]),
        volume_m3=v,
        principal_inertia_per_density_m5=_frozen(np.full(3, 0.4 * v * r * r)),
    )


def double_clump(r1_m: float, r2_m: float, overlap_factor: float = 1.0) -> ClumpTemplate:
    """Thesis elongated clump: centre distance D = C (R1 + R2), C in [0.5, 1] (Eq. 4.10)."""
    r1, r2, c = float(r1_m), float(r2_m), float(overlap_factor)
    if not (r1 > 0 and r2 > 0):
        raise ValueError(f"double clump radii must be > 0, got r1_m={r1_m}, r2_m={r2_m}")
    if not 0.5 <= c <= 1.0:
        raise ValueError(
            f"overlap_factor C must be in [0.5, 1] (D = C (R1 + R2), thesis Eq. 4.10), got {overlap_factor}"
        )
    d = c * (r1 + r2)
    t = from_spheres(np.array([[0.0, 0.0, 0.0], [d, 0.0, 0.0]]), np.array([r1, r2]), name="double_clump")
    return t


def pyramid(radius_m: float) -> ClumpTemplate:
    """Four equal touching spheres on the vertices of a regular tetrahedron (edge 2r)."""
    r = float(radius_m)
    if not r > 0:
        raise ValueError(f"radius_m must be > 0, got {radius_m}")
    s = r / np.sqrt(2.0)
    verts = s * np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=np.float64)
    return from_spheres(verts, np.full(4, r), name="pyramid")
