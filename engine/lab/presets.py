"""Fidelity presets: a bundled rig record, particles and simulation settings under one old name.

The apparatus (dimensions, gap, loads, speeds) is data: the bundled rig records of ``engine/lab/rig_records``
(``engine.lab.rigs``); ``lab_setup`` turns a record into the ``Fidelity`` the procedures read. What is left
here is what no apparatus holds: the particles each fidelity puts in its rig and the speed factor.

"thesis" is the set-up of chapters 4 and 5 (590 x 330 mm shear box split at mid-height with a
1 mm gap, the three clump shapes of Tables 4.2/4.9, loads of Table 3.1). "screening" is the
Appendix A set-up (Table A.7: container radius 200 mm, packing depth 370 mm, mono-sized spheres
of radius 20 mm, ~840 particles, DST loads 1,885 / 3,495 / 5,105 / 6,760 N and a CCT force of
8,415 N), whose forces are turned into stresses over the container area, so that conditions
are stresses at both fidelities (8,415 N over pi 0.2^2 is 67.0 kPa, close to the 65.6 kPa of
Table 3.1: Appendix A chose its forces to give the same stresses in the smaller box).

Lab speeds are the thesis's (lid 1 mm/s; shear 1 mm/s, 0.3 mm/s in Appendix A; bucket 5 mm/s);
the default speed factors are what keeps a run affordable while the inertial number stays
in the quasi-static range (docs/lab.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

from engine.lab.errors import SpecFieldError
from engine.lab.rigs import Rig, bundled_rig, check_for_particles
from engine.particles.description import Particles, thesis_particles


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
    """One lab set-up as the procedures read it: a rig record's apparatus with particles and the
    simulation's settings (``lab_setup``)."""

    name: str
    rig_name: str
    container_radius_m: float
    container_height_m: float
    packing_height_m: float  # levelling height
    split_height_m: float
    gap_m: float
    shapes: tuple[ShapeFraction, ...]
    dst_normal_stresses_pa: tuple[float, ...]
    cct_max_stress_pa: float
    cct_cycles: int
    lab_lid_speed_m_s: float
    lab_shear_speed_m_s: float
    shear_distance_m: float
    default_speed_factor: float
    lid_start_gap_m: float = 0.030
    # what a battery runs by default beyond the apparatus (options.stop_after_reduced, options.dst_speed_by_stress):
    # on at screening, where the loop runs its batteries (docs/lab.md, fewer steps per battery); off at thesis
    # fidelity, whose runs are the thesis-comparison tables
    stop_after_reduced: bool = False
    dst_speed_by_stress: bool = False
    residual_window: tuple[float, float] = (0.08, 0.10)
    fill_margin: float = 1.15  # particles inserted / particles expected below the level
    expected_solid_fraction: float = 0.58
    # height the rainfall column has already fallen when it is inserted (m): it starts with the
    # free-fall speed sqrt(2 g h), which is exactly a drop from h higher, without simulating the fall
    rain_drop_height_m: float = 0.0
    aor: AorGeometry | None = None
    # particles of the angle-of-repose test when they differ from the fill's (None: the same)
    aor_shapes: tuple[ShapeFraction, ...] | None = None
    anchor: AnchorGeometry | None = None
    rig: Rig | None = field(default=None, repr=False, compare=False)  # the record it was built from

    def rig_warnings(self) -> list[str]:
        """The rig checked against the shear-box particles (``engine.lab.rigs.check_for_particles``): raises
        ``SpecFieldError`` naming the rig's field when they cannot run in it, else the size warnings."""
        return [] if self.rig is None else check_for_particles(self.rig, particles_of(self.shapes))

    @property
    def container_area_m2(self) -> float:
        return math.pi * self.container_radius_m**2

    @property
    def container_diameter_m(self) -> float:
        return 2.0 * self.container_radius_m


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
              aor_shapes: tuple[ShapeFraction, ...] | None = None, stop_after_reduced: bool = False,
              dst_speed_by_stress: bool = False) -> Fidelity:
    """The set-up the procedures read: the rig record's apparatus, the particles, and the simulation's own
    settings (speed factor and the fill's margins, which are not part of any apparatus)."""
    box, fill, aor, anchor = rig.shear_box, rig.fill, rig.angle_of_repose, rig.anchor
    if box is None or fill is None or aor is None or anchor is None:
        missing = [k for k in ("shear_box", "fill", "angle_of_repose", "anchor") if getattr(rig, k) is None]
        raise SpecFieldError("rig", f"rig {rig.name!r} has no {', '.join(missing)}: a battery needs every section")
    return Fidelity(
        name=name,
        rig_name=rig.name,
        rig=rig,
        container_radius_m=box.container_radius_m,
        container_height_m=box.container_height_m,
        packing_height_m=fill.level_height_m,
        split_height_m=box.bottom_half_height_m,
        gap_m=box.gap_m,
        shapes=shapes,
        dst_normal_stresses_pa=box.dst_stresses_pa,
        cct_max_stress_pa=box.cct_stress_pa,
        cct_cycles=box.cct_cycles,
        lab_lid_speed_m_s=box.lid_speed_m_s,
        lab_shear_speed_m_s=box.shear_speed_m_s,
        shear_distance_m=box.shear_distance_m,
        default_speed_factor=default_speed_factor,
        stop_after_reduced=stop_after_reduced,
        dst_speed_by_stress=dst_speed_by_stress,
        lid_start_gap_m=box.lid_start_gap_m,
        rain_drop_height_m=fill.drop_height_m,
        aor=AorGeometry(bucket_bottom_radius_m=0.5 * aor.bucket_bottom_diameter_m,
                        bucket_top_radius_m=0.5 * aor.bucket_top_diameter_m,
                        bucket_height_m=aor.bucket_height_m, fill_height_m=aor.fill_height_m,
                        lift_speed_m_s=aor.lift_speed_m_s, wide_end_down=aor.wide_end_down,
                        bucket_friction=aor.bucket_friction, floor_friction=aor.floor_friction),
        aor_shapes=aor_shapes,
        anchor=AnchorGeometry(tube_width_m=anchor.tube_width_m, tube_length_m=anchor.tube_length_m,
                              plate_width_m=anchor.plate_width_m, plate_thickness_m=anchor.plate_thickness_m,
                              bin_width_m=anchor.bin_width_m, packing_height_m=anchor.packing_height_m,
                              pull_speed_m_s=anchor.pull_speed_m_s, acceleration_time_s=anchor.acceleration_time_s,
                              pull_distance_m=anchor.pull_distance_m, anchor_friction=anchor.anchor_friction,
                              bin_friction=anchor.bin_friction),
    )


# the fidelities' rigs: the old word names the bundled record it always meant
FIDELITY_RIGS = {"thesis": "thesis-590mm-shear-box", "screening": "appendix-a-400mm-shear-box"}

# The thesis's own particles (Table 4.2 clump mix) in its own rig (the 590 mm box).
THESIS = lab_setup("thesis", bundled_rig(FIDELITY_RIGS["thesis"]), shape_fractions(thesis_particles()),
                   default_speed_factor=10.0)

# Appendix A: mono-sized spheres of radius 20 mm in the 400 mm box (~840 particles).
# Spheres without rolling resistance roll away on a flat floor and form no pile at all, so the
# screening angle of repose uses pyramid clumps (four spheres of half the screening radius, about
# the same grain size) in the rig's bucket, the thesis's scaled by 0.6 (~120 clumps after levelling
# instead of ~600). Its 156 mm opening is only ~4 clump sizes (the thesis's: ~7): narrow end down, the
# converging wall wedges the grains and a slow lift carries a plug up with the bucket, so the scaled
# bucket stands on its wide rim. Lift 20 mm/s, not 5 mm/s: at 50 or 100 mm/s the column collapses
# instead of draining through the gap under the rim, and the pile comes out flatter. docs/lab.md.
SCREENING = lab_setup("screening", bundled_rig(FIDELITY_RIGS["screening"]),
                      (ShapeFraction("sphere", 0.020, 0.020, 1.0),), default_speed_factor=40.0,
                      aor_shapes=(ShapeFraction("pyramid", 0.010, 0.010, 1.0),),
                      stop_after_reduced=True, dst_speed_by_stress=True)

FIDELITIES = {"thesis": THESIS, "screening": SCREENING}


def fidelity(name: str, particle_radius_m: float | None = None, clump_aspect_ratio: float = 1.0) -> Fidelity:
    """The preset by name; at screening, ``particle_radius_m`` replaces the 20 mm spheres (the thesis
    fidelity has its own clump mix, Table 4.2). ``clump_aspect_ratio`` > 1 makes the mix's spheres
    two-sphere clumps of that length/width with the solid volume of the sphere they replace
    (``engine/lab/shape.py``): every shear-box (and anchor-bin) grain at screening, the round 20.8 % at
    the thesis fidelity. The screening angle of repose keeps its pyramids (spheres would roll away, see
    the preset), so the shape does not reach it there.
    """
    try:
        preset = FIDELITIES[name]
    except KeyError:
        raise SpecFieldError("fidelity", f"unknown fidelity {name!r}; choose one of {sorted(FIDELITIES)}") from None
    if particle_radius_m is not None:
        if name != "screening":
            raise SpecFieldError("parameters.particle_radius_m", "particle_radius_m applies to the screening fidelity only")
        half = 0.5 * particle_radius_m
        preset = replace(preset, shapes=(ShapeFraction("sphere", particle_radius_m, particle_radius_m, 1.0),),
                         aor_shapes=(ShapeFraction("pyramid", half, half, 1.0),))
    if clump_aspect_ratio != 1.0:
        from engine.lab.shape import elongated_shapes

        preset = replace(preset, shapes=elongated_shapes(clump_aspect_ratio, preset.shapes))
    return preset
