"""Size distributions and shape mixes by solid-volume fraction (thesis Section 4.2, Tables 4.2 and 4.9).

Sizes are *sphere radii*: for a sphere its radius, for the pyramid the radius
of its four equal spheres, for the elongated (double) clump each of its two
radii, drawn independently as the thesis's code generator did, and for a user
sphere set the radius of its largest sphere (the set is scaled to it).

Gaussian sizes: the thesis (and PFC's ``generate ... gauss``) give only R_min
and R_max. We take the mean at the midpoint and the standard deviation
(R_max - R_min)/6, so that +-3 sd spans the range and 99.7 % of an untruncated
draw would fall in it; draws are truncated to [R_min, R_max] exactly (inverse
CDF), and both moments can be overridden.

Shape mix: the thesis fixes *volume* fractions (pyramid 37.5 %, elongated
41.7 %, sphere 20.8 %), so each new particle is given to the component whose
solid volume lags most behind its target share (greedy deficit rule). The
fractions are then met to within one particle's volume, whatever the sizes.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal, Protocol

import numpy as np
from scipy.special import ndtr, ndtri

from . import templates as tpl


class SizeDistribution(Protocol):
    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray: ...


def _check_range(r_min_m, r_max_m, what):
    if not (np.isfinite(r_min_m) and np.isfinite(r_max_m) and 0 < r_min_m <= r_max_m):
        raise ValueError(f"{what}: need 0 < r_min_m <= r_max_m, got r_min_m={r_min_m}, r_max_m={r_max_m}")


@dataclass(frozen=True)
class ConstantSize:
    radius_m: float

    def __post_init__(self):
        _check_range(self.radius_m, self.radius_m, "constant size")

    def sample(self, rng, n):
        return np.full(int(n), float(self.radius_m))


@dataclass(frozen=True)
class UniformSize:
    r_min_m: float
    r_max_m: float

    def __post_init__(self):
        _check_range(self.r_min_m, self.r_max_m, "uniform size")

    def sample(self, rng, n):
        return self.r_min_m + (self.r_max_m - self.r_min_m) * rng.random(int(n))


@dataclass(frozen=True)
class TruncatedGaussian:
    """Gaussian radii truncated to [r_min_m, r_max_m]; mean/sd default to midpoint and range/6."""

    r_min_m: float
    r_max_m: float
    mean_m: float | None = None
    sd_m: float | None = None

    def __post_init__(self):
        _check_range(self.r_min_m, self.r_max_m, "Gaussian size")
        if self.sd_m is not None and not self.sd_m > 0:
            raise ValueError(f"Gaussian size: sd_m must be > 0, got {self.sd_m}")

    @property
    def mean(self) -> float:
        return 0.5 * (self.r_min_m + self.r_max_m) if self.mean_m is None else float(self.mean_m)

    @property
    def sd(self) -> float:
        return (self.r_max_m - self.r_min_m) / 6.0 if self.sd_m is None else float(self.sd_m)

    def sample(self, rng, n):
        if self.r_max_m == self.r_min_m:
            return np.full(int(n), float(self.r_min_m))
        a = ndtr((self.r_min_m - self.mean) / self.sd)
        b = ndtr((self.r_max_m - self.mean) / self.sd)
        u = a + (b - a) * rng.random(int(n))
        return np.clip(self.mean + self.sd * ndtri(u), self.r_min_m, self.r_max_m)


@dataclass(frozen=True)
class DiscreteSizes:
    """A few radius classes with number fractions (e.g. the LIGGGHTS benchmark's 10/12.5/15 mm)."""

    radii_m: tuple[float, ...]
    number_fractions: tuple[float, ...]

    def __post_init__(self):
        r, f = np.asarray(self.radii_m, float), np.asarray(self.number_fractions, float)
        if r.ndim != 1 or r.shape != f.shape or r.size == 0 or np.any(r <= 0) or np.any(f < 0) or f.sum() <= 0:
            raise ValueError("discrete sizes: radii_m > 0 and number_fractions >= 0 of equal length, fractions not all 0")

    def sample(self, rng, n):
        f = np.asarray(self.number_fractions, float)
        return np.asarray(self.radii_m, float)[rng.choice(len(f), size=int(n), p=f / f.sum())]


@dataclass(frozen=True)
class SievePSD:
    """User particle-size distribution: sieve sizes (m, increasing) and cumulative mass fraction passing.

    The sieve size is taken as a sphere diameter (radius = size/2). Between two
    sieves mass is spread uniformly in size (linear interpolation of the
    cumulative curve), so the number density there is proportional to
    size^-3; each particle's bin is drawn by number weight and its size by the
    exact inverse CDF of size^-3 within the bin. The mass-weighted cumulative
    curve of a large sample therefore reproduces the input curve.
    """

    sieve_sizes_m: tuple[float, ...]
    cumulative_passing: tuple[float, ...]

    def __post_init__(self):
        d, p = np.asarray(self.sieve_sizes_m, float), np.asarray(self.cumulative_passing, float)
        if d.ndim != 1 or d.shape != p.shape or d.size < 2:
            raise ValueError("PSD: sieve_sizes_m and cumulative_passing need equal length >= 2")
        if np.any(d <= 0) or np.any(np.diff(d) <= 0):
            raise ValueError("PSD: sieve_sizes_m must be > 0 and strictly increasing")
        if np.any(np.diff(p) < 0) or p[0] < 0 or abs(p[-1] - 1.0) > 1e-9:
            raise ValueError("PSD: cumulative_passing must be non-decreasing, >= 0 and end at 1 (fraction, by mass)")

    def sample(self, rng, n):
        d = np.asarray(self.sieve_sizes_m, float)
        p = np.asarray(self.cumulative_passing, float)
        lo, hi, mass = d[:-1], d[1:], np.diff(p)
        # mass density per unit size in the bin is mass/(hi-lo); number weight = that / size^3 integrated
        number = mass / (hi - lo) * 0.5 * (lo**-2 - hi**-2)
        bins = rng.choice(len(number), size=int(n), p=number / number.sum())
        a, b = lo[bins], hi[bins]
        u = rng.random(int(n))
        size = (a**-2 - u * (a**-2 - b**-2)) ** -0.5
        return 0.5 * size

    def mass_passing(self, radii_m: np.ndarray, mass_weights: np.ndarray | None = None) -> np.ndarray:
        """Cumulative mass fraction of a sample passing each sieve (to compare with the input curve)."""
        size = 2.0 * np.asarray(radii_m, float)
        w = size**3 if mass_weights is None else np.asarray(mass_weights, float)
        return np.array([w[size <= s].sum() for s in self.sieve_sizes_m]) / w.sum()


# ----------------------------------------------------------------------------- what a size form says

# radii drawn (seed 0) to describe a size form without a closed-form distribution (a sieve curve, discrete sizes)
SAMPLED_RADII = 65_536
_CLOSED_FORMS = {ConstantSize: "constant", UniformSize: "uniform", TruncatedGaussian: "truncated_gaussian"}


def _sampled(size) -> np.ndarray:
    return size.sample(np.random.default_rng(0), SAMPLED_RADII)


def number_cdf(size, radii_m) -> np.ndarray | None:
    """P(radius <= r) of a closed-form size distribution at each r; None for a form without one."""
    r = np.asarray(radii_m, float)
    if isinstance(size, ConstantSize):
        return (r >= size.radius_m).astype(float)
    if isinstance(size, UniformSize):
        if size.r_max_m == size.r_min_m:
            return (r >= size.r_min_m).astype(float)
        return np.clip((r - size.r_min_m) / (size.r_max_m - size.r_min_m), 0.0, 1.0)
    if isinstance(size, TruncatedGaussian):
        if size.r_max_m == size.r_min_m:
            return (r >= size.r_min_m).astype(float)
        a, b = (ndtr((x - size.mean) / size.sd) for x in (size.r_min_m, size.r_max_m))
        return np.clip((ndtr((r - size.mean) / size.sd) - a) / (b - a), 0.0, 1.0)
    return None


def bin_shares(size, edges_m) -> np.ndarray:
    """Number probability of each interval between consecutive ``edges_m`` (increasing): from the closed form
    where there is one, else the share of ``SAMPLED_RADII`` radii drawn at seed 0 (bins half-open, the last closed)."""
    edges = np.asarray(edges_m, float)
    cdf = number_cdf(size, edges)
    if cdf is None:
        counts, _ = np.histogram(_sampled(size), bins=edges)
        return counts / max(int(counts.sum()), 1)
    shares = np.diff(cdf)
    return shares / shares.sum() if shares.sum() > 0 else shares


def described(size) -> tuple[str, float, float]:
    """(kind, mean radius, sd of the radius): the closed form's ("constant", "uniform", "truncated_gaussian"), or
    "sampled" with the moments of ``SAMPLED_RADII`` radii drawn at seed 0."""
    kind = _CLOSED_FORMS.get(type(size))
    if kind == "constant":
        return kind, float(size.radius_m), 0.0
    if kind == "uniform":
        return kind, 0.5 * (size.r_min_m + size.r_max_m), (size.r_max_m - size.r_min_m) / 12.0 ** 0.5
    if kind == "truncated_gaussian":
        return kind, size.mean, size.sd
    radii = _sampled(size)
    return "sampled", float(radii.mean()), float(radii.std())


# ----------------------------------------------------------------------------- shapes

ShapeName = Literal["sphere", "pyramid", "double_clump", "custom"]


@dataclass(frozen=True)
class ShapeComponent:
    """One shape of a mix: its kind, sphere-radius distribution and share of the solid volume."""

    shape: ShapeName
    size: SizeDistribution
    volume_fraction: float
    overlap_factor: float = 1.0
    custom: tpl.ClumpTemplate | None = None

    def __post_init__(self):
        if self.shape not in ("sphere", "pyramid", "double_clump", "custom"):
            raise ValueError(f"shape must be sphere, pyramid, double_clump or custom, got {self.shape!r}")
        if not 0 <= self.volume_fraction <= 1:
            raise ValueError(f"volume_fraction must be in [0, 1], got {self.volume_fraction}")
        if self.shape == "double_clump" and not 0.5 <= self.overlap_factor <= 1.0:
            raise ValueError(f"overlap_factor C must be in [0.5, 1] (thesis Eq. 4.10), got {self.overlap_factor}")
        if self.shape == "custom" and self.custom is None:
            raise ValueError("shape 'custom' needs a ClumpTemplate in `custom`")

    def make(self, rng, n) -> list[tpl.ClumpTemplate]:
        if self.shape == "double_clump":
            r = self.size.sample(rng, 2 * n).reshape(n, 2)
            return [tpl.double_clump(a, b, self.overlap_factor) for a, b in r]
        r = self.size.sample(rng, n)
        if self.shape == "sphere":
            return [tpl.sphere(x) for x in r]
        unit = tpl.pyramid(1.0) if self.shape == "pyramid" else self.custom
        ref = float(unit.sphere_radii_m.max())
        return [unit.scaled(x / ref) for x in r]


@dataclass(frozen=True)
class ShapeMix:
    components: tuple[ShapeComponent, ...] = field(default_factory=tuple)

    def __post_init__(self):
        if not self.components:
            raise ValueError("a shape mix needs at least one component")
        total = sum(c.volume_fraction for c in self.components)
        if abs(total - 1.0) > 1e-3:
            raise ValueError(f"shape volume fractions must add up to 1 (100 %), got {total:.4f}")

    def sample(self, rng, count: int | None = None, solid_volume_m3: float | None = None):
        """Templates for ``count`` bodies, or for bodies until ``solid_volume_m3`` is reached.

        Returns (templates, component_index); templates[i] belongs to body i.
        """
        if (count is None) == (solid_volume_m3 is None):
            raise ValueError("give exactly one of count or solid_volume_m3")
        if count is not None and count < 0:
            raise ValueError(f"count must be >= 0, got {count}")
        if solid_volume_m3 is not None and not solid_volume_m3 > 0:
            raise ValueError(f"solid_volume_m3 must be > 0, got {solid_volume_m3}")
        rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
        frac = np.array([c.volume_fraction for c in self.components], float)
        active = frac > 0
        # pre-draw candidate bodies per component in blocks, in a fixed order, for reproducibility
        pools: list[list] = [[] for _ in self.components]
        vol = np.zeros(len(self.components))
        out, comp = [], []
        while True:
            if count is not None and len(out) >= count:
                break
            if solid_volume_m3 is not None and vol.sum() >= solid_volume_m3:
                break
            lag = np.where(active, vol / np.where(active, frac, 1.0), np.inf)
            k = int(np.argmin(lag))  # ties: first component
            if not pools[k]:
                pools[k] = self.components[k].make(rng, 256)[::-1]
            t = pools[k].pop()
            out.append(t)
            comp.append(k)
            vol[k] += t.volume_m3
        return out, np.asarray(comp, dtype=np.int64)


def thesis_shape_mix(overlap_factor: float = 1.0) -> ShapeMix:
    """Thesis Tables 4.2 / 4.9: pyramid 7.5-10.5 mm 37.5 %, elongated 12-15 mm 41.7 %, sphere 15-16.2 mm 20.8 %."""
    return ShapeMix((
        ShapeComponent("pyramid", TruncatedGaussian(7.5e-3, 10.5e-3), 0.375),
        ShapeComponent("double_clump", TruncatedGaussian(12.0e-3, 15.0e-3), 0.417, overlap_factor=overlap_factor),
        ShapeComponent("sphere", TruncatedGaussian(15.0e-3, 16.2e-3), 0.208),
    ))
