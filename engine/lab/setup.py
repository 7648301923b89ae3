"""One lab set-up as the procedures read it: a rig record, the particles built in it, the simulation's settings.

Why a module of its own: the presets (``engine.lab.presets``: the old fidelity names) and the resolutions
(``engine.lab.resolution``: a material's particles, as measured or coarse-grained, in the rig its measurements
were made in) both end in the same set-up; the procedures, the cost model and the checks read only this.
The apparatus is the rig record (``engine.lab.rigs``) and is read from it, not copied.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from engine.lab.errors import SpecFieldError
from engine.lab.rigs import Rig, check_for_particles
from engine.particles.description import Particles


@dataclass(frozen=True)
class ShapeFraction:
    """One clump shape of a mix: template name, sphere radius bounds (Gaussian between them), volume share.

    ``shape`` "custom" takes its body from ``template`` (an ``engine.particles.templates.ClumpTemplate``
    whose largest sphere has radius ``radius_min_m`` = ``radius_max_m``), e.g. the elongated screening
    grains of ``engine/lab/shape.py``.
    """

    shape: str
    radius_min_m: float
    radius_max_m: float
    volume_fraction: float
    template: Any = None
    # a size distribution other than the Gaussian between the bounds (engine.particles.distributions),
    # e.g. a sieve curve; None: Gaussian between radius_min_m and radius_max_m (constant when equal)
    size: Any = None
    overlap_factor: float = 1.0  # double_clump only: the thesis's C (Eq. 4.10)


@dataclass(frozen=True)
class AorGeometry:
    """The angle-of-repose bucket as the procedure reads it (radii; from the rig record's diameters)."""

    bucket_bottom_radius_m: float
    bucket_top_radius_m: float
    bucket_height_m: float
    fill_height_m: float
    lift_speed_m_s: float
    # the thesis's bucket stands on its (cut-off) bottom, narrow end down (section 5.2.1);
    # True stands it on its wide rim, so that lifting it moves the wall away from the grains
    wide_end_down: bool
    bucket_friction: float
    floor_friction: float
    scale: float = 1.0  # the rig records give the bucket's own dimensions: 1


@dataclass(frozen=True)
class AnchorGeometry:
    """The anchor pull-out bin and anchor as the procedure reads them (engine.lab.rigs.Anchor)."""

    tube_width_m: float
    tube_length_m: float
    plate_width_m: float
    plate_thickness_m: float
    bin_width_m: float
    packing_height_m: float
    pull_speed_m_s: float
    acceleration_time_s: float
    pull_distance_m: float
    anchor_friction: float
    bin_friction: float


@dataclass(frozen=True)
class Fidelity:
    """One lab set-up as the procedures read it: a rig record (the apparatus), the particles built in it at
    one resolution, and the simulation's own settings (speed factor, the fill's margins).

    The apparatus is read from ``rig`` and nowhere else: the properties below are the record's numbers under
    the names the procedures use (radii where the record gives diameters), not a copy of them.
    """

    name: str
    rig: Rig
    shapes: tuple[ShapeFraction, ...]
    default_speed_factor: float
    residual_window: tuple[float, float] = (0.08, 0.10)
    fill_margin: float = 1.15  # particles inserted / particles expected below the level
    expected_solid_fraction: float = 0.58
    # particles of the angle-of-repose test when they differ from the fill's (None: the same)
    aor_shapes: tuple[ShapeFraction, ...] | None = None
    # the resolution's size factor: particle sizes over the material's (1: as measured; engine.lab.resolution)
    scale_factor: float = 1.0
    # the description ``shapes`` were built from (None: shapes set otherwise, e.g. a screening radius)
    particles: Particles | None = None
    # what a battery runs by default beyond the apparatus (options.stop_after_reduced, options.dst_speed_by_stress):
    # on at screening, where the loop runs its batteries (docs/lab.md, fewer steps per battery); off at thesis
    # fidelity, whose runs are the thesis-comparison tables
    stop_after_reduced: bool = False
    dst_speed_by_stress: bool = False
    # how the fill reads its packing height (engine.lab.rigs.Fill.height_rule): a material's set-up reads it as
    # its rig's laboratory did; the presets keep the thesis's DEM rule, so that their runs are the thesis tables'
    fill_height_rule: str = "highest_sphere_top"

    def rig_warnings(self) -> list[str]:
        """The rig checked against the shear-box particles (``engine.lab.rigs.check_for_particles``): raises
        ``SpecFieldError`` naming the rig's field when they cannot run in it, else the size warnings."""
        return check_for_particles(self.rig, particles_of(self.shapes))

    # ----------------------------------------------------------------- the record's sections
    @property
    def _box(self):
        return _section(self.rig, "shear_box")

    @property
    def rig_name(self) -> str:
        return self.rig.name

    @property
    def container_radius_m(self) -> float:
        return self._box.container_radius_m

    @property
    def container_height_m(self) -> float:
        return self._box.container_height_m

    @property
    def packing_height_m(self) -> float:
        """The levelling height: the fill's, the brim without a fill section."""
        fill = self.rig.fill
        return fill.level_height_m if fill is not None else self._box.container_height_m

    @property
    def split_height_m(self) -> float:
        return self._box.bottom_half_height_m

    @property
    def gap_m(self) -> float:
        return self._box.gap_m

    @property
    def dst_normal_stresses_pa(self) -> tuple[float, ...]:
        return self._box.dst_stresses_pa

    @property
    def cct_max_stress_pa(self) -> float:
        return self._box.cct_stress_pa

    @property
    def cct_cycles(self) -> int:
        return self._box.cct_cycles

    @property
    def lab_lid_speed_m_s(self) -> float:
        return self._box.lid_speed_m_s

    @property
    def lab_shear_speed_m_s(self) -> float:
        return self._box.shear_speed_m_s

    @property
    def shear_distance_m(self) -> float:
        return self._box.shear_distance_m

    @property
    def lid_start_gap_m(self) -> float:
        return self._box.lid_start_gap_m

    @property
    def rain_drop_height_m(self) -> float:
        """Height the rainfall column has already fallen when it is inserted (m): it starts with the free-fall
        speed sqrt(2 g h), which is exactly a drop from h higher, without simulating the fall."""
        return self.rig.fill.drop_height_m if self.rig.fill is not None else 0.0

    @property
    def aor(self) -> AorGeometry:
        a = _section(self.rig, "angle_of_repose")
        return AorGeometry(bucket_bottom_radius_m=0.5 * a.bucket_bottom_diameter_m,
                           bucket_top_radius_m=0.5 * a.bucket_top_diameter_m,
                           bucket_height_m=a.bucket_height_m, fill_height_m=a.fill_height_m,
                           lift_speed_m_s=a.lift_speed_m_s, wide_end_down=a.wide_end_down,
                           bucket_friction=a.bucket_friction, floor_friction=a.floor_friction)

    @property
    def anchor(self) -> AnchorGeometry:
        a = _section(self.rig, "anchor")
        return AnchorGeometry(**{f: getattr(a, f) for f in AnchorGeometry.__dataclass_fields__})

    @property
    def container_area_m2(self) -> float:
        return math.pi * self.container_radius_m**2

    @property
    def container_diameter_m(self) -> float:
        return 2.0 * self.container_radius_m


def _section(rig: Rig, name: str):
    section = getattr(rig, name)
    if section is None:
        raise SpecFieldError("rig", f"rig {rig.name!r} has no {name} section")
    return section


def shape_fractions(particles: Particles) -> tuple[ShapeFraction, ...]:
    """A material's particles as the lab's shape list: a Gaussian or constant size keeps its radius bounds
    (what the fill has always drawn from); any other form rides along as its distribution."""
    out = []
    for s in particles.shapes:
        size = particles.size_of(s)
        low, high = size.radius_range_m
        shape = "double_clump" if s.shape == "elongated" else s.shape
        plain = size.form in ("gaussian", "constant") and getattr(size, "mean_m", None) is None \
            and getattr(size, "sd_m", None) is None
        # a custom clump always carries its distribution: it is scaled to each drawn size, while a template
        # without one is a single fixed body (the screening elongated grains, engine/lab/shape.py)
        keep = plain and s.template is None
        out.append(ShapeFraction(shape, low, high, s.volume_fraction, template=s.template,
                                 size=None if keep else size.distribution(), overlap_factor=s.overlap_factor))
    return tuple(out)


def particles_of(shapes: tuple[ShapeFraction, ...]) -> Particles:
    """The lab's shape list as a ``Particles`` description (the other way from ``shape_fractions``), for the
    checks that take one: sizes as their radius bounds, a fixed template as a custom clump of its size."""
    out = []
    for s in shapes:
        size = ({"form": "constant", "radius_m": s.radius_min_m} if s.radius_min_m == s.radius_max_m
                else {"form": "uniform", "radius_min_m": s.radius_min_m, "radius_max_m": s.radius_max_m})
        entry = {"shape": "elongated" if s.shape == "double_clump" else s.shape, "volume_fraction": s.volume_fraction,
                 "size": size}
        if s.shape == "double_clump":
            entry["aspect_ratio"] = 1.0 + s.overlap_factor
        if s.template is not None:
            entry.update(shape="custom", sphere_centres_m=[list(map(float, c)) for c in s.template.sphere_offsets_m],
                         sphere_radii_m=[float(r) for r in s.template.sphere_radii_m])
        out.append(entry)
    return Particles.model_validate({"shapes": out})


def lab_setup(name: str, rig: Rig, shapes: tuple[ShapeFraction, ...], *, default_speed_factor: float,
              aor_shapes: tuple[ShapeFraction, ...] | None = None, scale_factor: float = 1.0,
              particles: Particles | None = None, stop_after_reduced: bool = False,
              dst_speed_by_stress: bool = False, fill_height_rule: str = "highest_sphere_top") -> Fidelity:
    """The set-up the procedures read: the rig record's apparatus, the particles, and the simulation's own
    settings (speed factor and the fill's margins, which are not part of any apparatus). A rig may hold only
    the sections of the tests its laboratory runs: each test's (``LabTest.apparatus``) is checked when a job
    plans it (``RunContext.validate``), and a section read that the record lacks raises naming ``rig``."""
    return Fidelity(name=name, rig=rig, shapes=shapes, default_speed_factor=default_speed_factor,
                    aor_shapes=aor_shapes, scale_factor=scale_factor, particles=particles,
                    stop_after_reduced=stop_after_reduced, dst_speed_by_stress=dst_speed_by_stress,
                    fill_height_rule=fill_height_rule)
