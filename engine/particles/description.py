"""A material's particles as data: size distribution, solid density and shape, validated (SI).

Why a model beside ``distributions`` and ``templates``: those are the engine's building blocks (a sieve
curve, a truncated Gaussian, a clump template); a user names them in JSON. ``Particles`` is that JSON,
checked when it is sent (a 422 naming the field, not a failed job hours later), stored with the material
and turned into the engine's ``ShapeMix`` by ``shape_mix()``.

Sizes follow ``engine.particles.distributions``: the named forms give *sphere radii* (for a pyramid the
radius of its four spheres, for an elongated clump each of its two); a sieve curve gives sieve sizes
(taken as sphere diameters). A shape without its own size takes the material's ``size``.

Shapes: ``sphere``; ``elongated``, a two-sphere clump of length/width ``aspect_ratio`` (the thesis's
elongated clump, centre distance C (R1 + R2) with C = aspect_ratio - 1 in [0.5, 1], thesis Eq. 4.10);
``pyramid``, four equal touching spheres (thesis Figure 4.4); ``custom``, a clump template given by its
sphere centres and radii, scaled so that its largest sphere has the drawn radius. Several shapes form a
mix by *solid-volume* fraction, as the thesis specified its mix (Table 4.2).
"""
from __future__ import annotations

import math
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Annotated, Literal, Union

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from engine.particles import distributions as dist
from engine.particles import templates as tpl

# the lab's particle radius range (engine.lab.bounds: 10 um powders to 0.5 m boulders); kept here as
# numbers so that engine.particles does not import the lab
_MIN_RADIUS_M, _MAX_RADIUS_M = 1e-5, 0.5
_DENSEST_SOLID_KG_M3 = 22_590.0  # osmium (engine.lab.bounds.DENSEST_SOLID_KG_M3)
_MAX_SIEVES = 100
_MAX_SHAPES = 16
_MAX_CUSTOM_SPHERES = 64

_MODEL = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True, frozen=True)
_Radius = Annotated[float, Field(ge=_MIN_RADIUS_M, le=_MAX_RADIUS_M)]


class ConstantRadius(BaseModel):
    """Mono-sized: every sphere of the shape has this radius."""

    model_config = _MODEL
    form: Literal["constant"]
    radius_m: _Radius

    def distribution(self) -> dist.ConstantSize:
        return dist.ConstantSize(self.radius_m)

    @property
    def radius_range_m(self) -> tuple[float, float]:
        return self.radius_m, self.radius_m


class UniformRadius(BaseModel):
    model_config = _MODEL
    form: Literal["uniform"]
    radius_min_m: _Radius
    radius_max_m: _Radius

    @model_validator(mode="after")
    def _ordered(self):
        if self.radius_max_m < self.radius_min_m:
            raise ValueError("radius_max_m must be >= radius_min_m")
        return self

    def distribution(self) -> dist.UniformSize:
        return dist.UniformSize(self.radius_min_m, self.radius_max_m)

    @property
    def radius_range_m(self) -> tuple[float, float]:
        return self.radius_min_m, self.radius_max_m


class GaussianRadius(BaseModel):
    """Gaussian radii truncated to [radius_min_m, radius_max_m] (the thesis's and PFC's "gauss" sizes):
    mean at the midpoint and sd = range / 6 unless given (engine.particles.distributions.TruncatedGaussian)."""

    model_config = _MODEL
    form: Literal["gaussian"]
    radius_min_m: _Radius
    radius_max_m: _Radius
    mean_m: _Radius | None = None
    sd_m: float | None = Field(None, gt=0, le=_MAX_RADIUS_M)

    @model_validator(mode="after")
    def _ordered(self):
        if self.radius_max_m < self.radius_min_m:
            raise ValueError("radius_max_m must be >= radius_min_m")
        return self

    def distribution(self) -> dist.TruncatedGaussian:
        return dist.TruncatedGaussian(self.radius_min_m, self.radius_max_m, self.mean_m, self.sd_m)

    @property
    def radius_range_m(self) -> tuple[float, float]:
        return self.radius_min_m, self.radius_max_m


class SieveCurve(BaseModel):
    """A sieve analysis: sieve apertures (m, increasing) and the mass fraction passing each (0..1, the last 1).

    The first sieve is the smallest size present (its passing fraction is what is finer, usually 0)."""

    model_config = _MODEL
    form: Literal["sieve"]
    sieve_sizes_m: list[Annotated[float, Field(ge=2 * _MIN_RADIUS_M, le=2 * _MAX_RADIUS_M)]] = Field(
        ..., min_length=2, max_length=_MAX_SIEVES)
    passing_fractions: list[Annotated[float, Field(ge=0.0, le=1.0)]] = Field(..., min_length=2, max_length=_MAX_SIEVES)

    @model_validator(mode="after")
    def _curve(self):
        d, p = self.sieve_sizes_m, self.passing_fractions
        if len(d) != len(p):
            raise ValueError(f"sieve_sizes_m ({len(d)}) and passing_fractions ({len(p)}) need the same length")
        if any(b <= a for a, b in zip(d, d[1:])):
            raise ValueError("sieve_sizes_m must be strictly increasing")
        if any(b < a for a, b in zip(p, p[1:])):
            raise ValueError("passing_fractions must not decrease (cumulative mass passing)")
        if abs(p[-1] - 1.0) > 1e-9:
            raise ValueError(f"the largest sieve must pass everything (passing fraction 1), got {p[-1]:g}")
        if p[0] >= 1.0:
            raise ValueError("the smallest sieve passes everything: no size range is left")
        return self

    def distribution(self) -> dist.SievePSD:
        return dist.SievePSD(tuple(self.sieve_sizes_m), tuple(self.passing_fractions))

    @property
    def radius_range_m(self) -> tuple[float, float]:
        # mass first appears above the last sieve that passes nothing
        first = max(i for i, p in enumerate(self.passing_fractions) if p <= 0.0) if self.passing_fractions[0] <= 0 else 0
        return 0.5 * self.sieve_sizes_m[first], 0.5 * self.sieve_sizes_m[-1]


SizeSpec = Annotated[Union[ConstantRadius, UniformRadius, GaussianRadius, SieveCurve], Field(discriminator="form")]

ShapeKind = Literal["sphere", "elongated", "pyramid", "custom"]
# sieve size of a body per largest sphere radius: the smallest round hole it passes. A sphere and an
# elongated clump (end on) pass 2 r; a pyramid (regular tetrahedron of spheres, edge 2 r) seen along the
# axis through two opposite edges' midpoints projects its centres onto a square of half-diagonal r, so it
# passes a hole of diameter 2 (r + r) = 4 r.
_SIEVE_SIZE_PER_RADIUS = {"sphere": 2.0, "elongated": 2.0, "pyramid": 4.0}


class Shape(BaseModel):
    """One shape of the material and its share of the solid volume."""

    model_config = _MODEL
    shape: ShapeKind
    volume_fraction: float = Field(..., gt=0.0, le=1.0)
    size: SizeSpec | None = Field(None, description="this shape's sizes; unset: the material's `size`")
    aspect_ratio: float | None = Field(
        None, ge=1.5, le=2.0,
        description="elongated only: length / width of the two-sphere clump (thesis Eq. 4.10: centre distance "
                    "C (R1 + R2), C = aspect_ratio - 1 in [0.5, 1]; 2 = two touching spheres)")
    sphere_centres_m: list[Annotated[list[float], Field(min_length=3, max_length=3)]] | None = Field(
        None, min_length=1, max_length=_MAX_CUSTOM_SPHERES, description="custom only: sphere centres (any frame)")
    sphere_radii_m: list[Annotated[float, Field(gt=0.0, le=_MAX_RADIUS_M)]] | None = Field(
        None, min_length=1, max_length=_MAX_CUSTOM_SPHERES, description="custom only: sphere radii")

    @model_validator(mode="after")
    def _fields_of_shape(self):
        if self.shape == "elongated" and self.aspect_ratio is None:
            raise ValueError("an elongated shape needs aspect_ratio (1.5 to 2)")
        if self.shape != "elongated" and self.aspect_ratio is not None:
            raise ValueError(f"aspect_ratio applies to elongated shapes only, not {self.shape}")
        custom = self.sphere_centres_m is not None or self.sphere_radii_m is not None
        if self.shape == "custom":
            if self.sphere_centres_m is None or self.sphere_radii_m is None:
                raise ValueError("a custom shape needs sphere_centres_m and sphere_radii_m")
            if len(self.sphere_centres_m) != len(self.sphere_radii_m):
                raise ValueError("sphere_centres_m and sphere_radii_m need the same length")
            if not all(math.isfinite(x) and abs(x) <= 10 * _MAX_RADIUS_M for c in self.sphere_centres_m for x in c):
                raise ValueError("sphere_centres_m must be finite and within 5 m")
        elif custom:
            raise ValueError(f"sphere_centres_m and sphere_radii_m apply to custom shapes only, not {self.shape}")
        return self

    @cached_property
    def template(self) -> tpl.ClumpTemplate | None:
        """The custom clump's template (mass properties of the union of its spheres); None for the others."""
        if self.shape != "custom":
            return None
        return tpl.from_spheres(np.asarray(self.sphere_centres_m, float), np.asarray(self.sphere_radii_m, float),
                                name="custom")

    @property
    def overlap_factor(self) -> float:
        """The thesis's C of an elongated clump (1 for the other shapes, where it is unused)."""
        return 1.0 if self.aspect_ratio is None else self.aspect_ratio - 1.0

    def sieve_size_per_radius(self) -> float:
        """Smallest round hole the body passes, per its largest sphere radius (see _SIEVE_SIZE_PER_RADIUS);
        a custom clump: ``template_sieve_size_m``."""
        if self.shape == "custom":
            return template_sieve_size_m(self.template) / float(np.max(self.template.sphere_radii_m))
        return _SIEVE_SIZE_PER_RADIUS[self.shape]


def template_sieve_size_m(template: tpl.ClumpTemplate) -> float:
    """An upper bound of the smallest round hole a clump passes: pushed through along each principal axis,
    the circle about its centre of mass that holds every sphere's projection; the narrowest of the three.
    Exact for a sphere and for spheres on one line (end on: the largest sphere's diameter)."""
    offsets = np.asarray(template.sphere_offsets_m, float)
    radii = np.asarray(template.sphere_radii_m, float)
    widths = []
    for axis in range(3):
        across = np.delete(offsets, axis, axis=1)
        widths.append(2.0 * float(np.max(np.linalg.norm(across, axis=1) + radii)))
    return min(widths)


class Particles(BaseModel):
    """What a material is made of, as the engine builds it (see the module docstring)."""

    model_config = _MODEL
    solid_density_kg_m3: float | None = Field(
        None, gt=0, le=_DENSEST_SOLID_KG_M3,
        description="density of the solid (not the bulk); unset: calibrated or taken from direct estimates")
    size: SizeSpec | None = Field(None, description="size distribution of every shape without its own")
    shapes: list[Shape] = Field(..., min_length=1, max_length=_MAX_SHAPES,
                                description="shapes and their solid-volume fractions (adding up to 1)")
    source: str = Field("", max_length=10_000)

    @model_validator(mode="after")
    def _mix(self):
        total = sum(s.volume_fraction for s in self.shapes)
        if abs(total - 1.0) > 1e-3:
            raise ValueError(f"shapes' volume_fraction must add up to 1, got {total:.4f}")
        for index, s in enumerate(self.shapes):
            if s.size is None and self.size is None:
                raise ValueError(f"shapes.{index} has no size and the material gives none (set `size`)")
        return self

    def size_of(self, shape: Shape) -> SizeSpec:
        return shape.size if shape.size is not None else self.size

    def shape_mix(self) -> dist.ShapeMix:
        """The engine's mix (``engine.particles.generation.generate`` takes it)."""
        components = []
        for s in self.shapes:
            size = self.size_of(s).distribution()
            if s.shape == "elongated":
                components.append(dist.ShapeComponent("double_clump", size, s.volume_fraction,
                                                      overlap_factor=s.overlap_factor))
            else:
                components.append(dist.ShapeComponent(s.shape, size, s.volume_fraction, custom=s.template))
        return dist.ShapeMix(tuple(components))

    @property
    def smallest_sphere_radius_m(self) -> float:
        """The smallest sphere any body can have (a custom clump scaled to its smallest size: its smallest sphere)."""
        radii = []
        for s in self.shapes:
            low = self.size_of(s).radius_range_m[0]
            if s.shape == "custom":
                low *= float(np.min(s.sphere_radii_m)) / float(np.max(s.sphere_radii_m))
            radii.append(low)
        return min(radii)

    @property
    def largest_sphere_radius_m(self) -> float:
        return max(self.size_of(s).radius_range_m[1] for s in self.shapes)

    @property
    def smallest_particle_size_m(self) -> float:
        """Sieve size of the smallest body: what slips through a gap (a sphere's diameter for spheres)."""
        return min(self.size_of(s).radius_range_m[0] * s.sieve_size_per_radius() for s in self.shapes)

    @property
    def largest_particle_size_m(self) -> float:
        """Sieve size of the largest body (the "maximum particle size" of the direct-shear standards)."""
        return max(self.size_of(s).radius_range_m[1] * s.sieve_size_per_radius() for s in self.shapes)


_THESIS_RECORD = Path(__file__).with_name("thesis_coarse_aggregate.json")


@lru_cache(maxsize=1)
def thesis_particles() -> Particles:
    """The seed thesis's aggregate as modelled (Tables 4.2 and 4.9): the bundled material carries the same."""
    return Particles.model_validate_json(_THESIS_RECORD.read_text())
