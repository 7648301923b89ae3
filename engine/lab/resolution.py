"""Resolution: how finely a simulation represents a material's particles, in the rig they were measured in.

Why: a measurement belongs to its apparatus (``engine.lab.rigs``) and a material to its particles
(``engine.particles.description``); what the calibration chooses is only how finely to model those
particles. "as measured" builds them as described; "coarse" scales every size by a factor s >= 1 and keeps
everything else: the solid density, the shapes and their volume fractions, and so the size distribution's
shape (a sieve curve's apertures are multiplied by s, its passing fractions unchanged). The rig stays the
rig, so a bulk mass, a packing height or a bulk stiffness is that of the container the measurement was made
in, at every resolution. Two things do change with s, and ``incomparable`` names them: the particle count
(~ 1/s^3 in a fixed container volume) and, beyond the limits below, what the box does to the shear band.

The factor is the user's (``scale_factor``) or proposed from a particle-count target (``target_particles``,
counted as the cost model counts them: spheres of the shear-box packing, ``engine.lab.cost.packing_spheres``):
in a container of fixed volume the count goes as 1/s^3, so s = (N_as_measured / N_target)^(1/3), never below 1.
The proposal stops at the direct-shear standards' sizes (ASTM D3080: box width >= 10 and specimen thickness
>= 6 largest particles, ``engine.lab.rigs``): past them the box, not the material, shapes the shear band. A
factor the user sets beyond them runs, with the rig's warning in the result (docs/lab.md, "Resolution").

The old fidelity names ("thesis", "screening") remain as aliases of the presets they always meant
(``engine.lab.presets``): a bundled rig, bundled particles and "as measured", so stored jobs and campaigns
replay with the same numbers.
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Annotated, Literal, Union

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, model_validator

from engine.lab.errors import SpecFieldError
from engine.lab.rigs import MIN_DIAMETER_PER_PARTICLE, MIN_THICKNESS_PER_PARTICLE, Rig
from engine.lab.setup import Fidelity, lab_setup, shape_fractions
from engine.lab.whole_number import bounded_whole_number
from engine.particles.description import Particles

AS_MEASURED = "as_measured"
COARSE = "coarse"
PRESET_NAMES = ("thesis", "screening")  # the old fidelity values, aliases of engine.lab.presets
# A coarse resolution without a factor or target aims at about the Appendix A screening packing's size
# (Table A.7: 836 spheres after levelling; the cost model counts its fill as 926, with the 15 % margin).
DEFAULT_TARGET_PARTICLES = 1000
# 100 x the material's sizes: a 1 mm grain as a 100 mm sphere. Beyond, no rig a lab builds holds ten of them.
MAX_SCALE_FACTOR = 100.0
# The simulation's speed factor (test speed / lab speed, docs/lab.md) where no preset gives one: the thesis's
# own, which keeps its particles quasi-static; coarser particles have a larger inertial number at the same
# speed, which the run checks and warns about (options.max_inertial_number).
DEFAULT_SPEED_FACTOR = 10.0

_MODEL = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True, frozen=True)
ParticleCount = bounded_whole_number(1, 10**9)


class Resolution(BaseModel):
    """``as_measured``, or ``coarse`` with a size factor or a particle-count target (neither: the default target)."""

    model_config = _MODEL
    mode: Literal["as_measured", "coarse"]
    scale_factor: float | None = Field(
        None, ge=1.0, le=MAX_SCALE_FACTOR,
        description="coarse only: particle sizes over the material's (2: twice the size, 1/8 of the particles)")
    target_particles: ParticleCount | None = Field(
        None,
        description="coarse only: demcal proposes the factor that gives about this many particles in the shear "
                    "box (as the cost model counts them), within the direct-shear standards' sizes")

    @model_validator(mode="after")
    def _one_way(self):
        given = [k for k in ("scale_factor", "target_particles") if getattr(self, k) is not None]
        if self.mode == AS_MEASURED and given:
            raise ValueError(f"{given[0]} applies to the coarse resolution only")
        if len(given) > 1:
            raise ValueError("give scale_factor or target_particles, not both")
        return self


def _form(value) -> str:
    """Which branch a value is judged by: a string by the names, anything else by the object. Without it
    pydantic tries both and a bad object was answered with the names' "Input should be 'thesis', ..." beside
    its real error (a client sending ``{"mode": "as_measured", "target_particles": 430}`` was told both)."""
    return "name" if isinstance(value, str) else "object"


# What a job or campaign sends: an old preset name, "as_measured", "coarse" (the default target), or the object.
# An error's location names the branch judged: ``resolution.name`` or ``resolution.object``.
ResolutionIn = Annotated[Union[Annotated[Literal["thesis", "screening", "as_measured", "coarse"], Tag("name")],
                               Annotated[Resolution, Tag("object")]], Discriminator(_form)]


def is_preset(resolution: ResolutionIn | None) -> bool:
    """None or an old fidelity name: the bundled set-up of ``engine.lab.presets``."""
    return resolution is None or resolution in PRESET_NAMES


def parsed(resolution: ResolutionIn) -> Resolution:
    """The object form of a material resolution ("as_measured" and "coarse" as names)."""
    if isinstance(resolution, Resolution):
        return resolution
    if resolution in PRESET_NAMES:
        raise ValueError(f"{resolution!r} is a preset, not a resolution of a material's particles")
    return Resolution(mode=resolution)


def label(resolution: ResolutionIn | None, fidelity: str) -> str:
    """A short name for listings (the jobs' and campaigns' ``fidelity`` column, 16 characters)."""
    if is_preset(resolution):
        return resolution or fidelity
    return parsed(resolution).mode


def scaled_size(size: dict, factor: float) -> dict:
    """A size description (engine.particles.description's forms, as JSON) with every length times ``factor``:
    radii, means, standard deviations and sieve apertures; fractions unchanged."""
    out = dict(size)
    for key in ("radius_m", "radius_min_m", "radius_max_m", "mean_m", "sd_m"):
        if out.get(key) is not None:
            out[key] = out[key] * factor
    if "sieve_sizes_m" in out:
        out["sieve_sizes_m"] = [d * factor for d in out["sieve_sizes_m"]]
    return out


def coarse_grained(particles: Particles, factor: float) -> Particles:
    """The material's particles with every size times ``factor``: solid density, shapes, aspect ratios,
    custom clumps (scaled to the drawn size anyway) and volume fractions kept. A size beyond the lab's largest
    particle is refused naming ``resolution.scale_factor``."""
    if factor == 1.0:
        return particles
    data = particles.model_dump(mode="json", exclude_none=True)
    if "size" in data:
        data["size"] = scaled_size(data["size"], factor)
    for shape in data["shapes"]:
        if "size" in shape:
            shape["size"] = scaled_size(shape["size"], factor)
    try:
        return Particles.model_validate(data)
    except ValueError as exc:
        raise SpecFieldError("resolution.scale_factor",
                             f"sizes x {factor:g} leave the lab's particle sizes: {_first_error(exc)}") from None


def _first_error(exc: ValueError) -> str:
    errors = getattr(exc, "errors", None)
    if errors is None:
        return str(exc)
    first = errors(include_url=False)[0]
    return f"{'.'.join(str(p) for p in first.get('loc', ()))}: {first.get('msg')}"


def packing_particles(rig: Rig, particles: Particles) -> int:
    """Particles of the shear-box packing as the cost model counts them (``engine.lab.cost.packing_spheres``)."""
    from engine.lab.cost import packing_spheres

    setup = lab_setup("count", rig, shape_fractions(particles), default_speed_factor=DEFAULT_SPEED_FACTOR)
    solids_m3 = setup.container_area_m2 * setup.packing_height_m * setup.expected_solid_fraction
    return packing_spheres(solids_m3, setup.fill_margin, setup.shapes)


def largest_valid_factor(rig: Rig, particles: Particles) -> float:
    """The largest size factor that keeps the rig within the direct-shear standards' sizes for these particles:
    box diameter >= 10 and specimen thickness (the fill level) >= 6 largest particles (``check_for_particles``)."""
    box, largest = rig.shear_box, particles.largest_particle_size_m
    if box is None:
        return MAX_SCALE_FACTOR
    thickness = rig.fill.level_height_m if rig.fill is not None else box.container_height_m
    return min(box.container_diameter_m / (MIN_DIAMETER_PER_PARTICLE * largest),
               thickness / (MIN_THICKNESS_PER_PARTICLE * largest), MAX_SCALE_FACTOR)


def factor_for_target(count_as_measured: int, target_particles: int) -> float:
    """The size factor that brings the packing from ``count_as_measured`` to ``target_particles`` particles: in
    a fixed container volume the count goes as 1/s^3. Never below 1 (a target above the as-measured count is
    met as measured)."""
    return max(1.0, (count_as_measured / target_particles) ** (1.0 / 3.0))


def scale_factor(rig: Rig, particles: Particles, resolution: Resolution) -> tuple[float, list[str]]:
    """The resolution's size factor in this rig for these particles, and notes on how it was chosen."""
    if resolution.mode == AS_MEASURED:
        return 1.0, []
    if resolution.scale_factor is not None:
        return float(resolution.scale_factor), []
    target = resolution.target_particles or DEFAULT_TARGET_PARTICLES
    count = packing_particles(rig, particles)
    wanted = factor_for_target(count, target)
    limit = max(1.0, largest_valid_factor(rig, particles))
    if wanted <= limit:
        return wanted, []
    return limit, [f"resolution: about {target} particles would need sizes x {wanted:.3g}, beyond x {limit:.3g} "
                   f"where rig {rig.name!r} stops meeting the direct-shear standards' sizes (10 largest particles "
                   f"across, 6 thick); x {limit:.3g} gives about {math.ceil(count / limit ** 3)}"]


def material_setup(rig: Rig, particles: Particles, resolution: ResolutionIn) -> tuple[Fidelity, list[str]]:
    """The lab set-up of a material's particles at ``resolution`` in the rig its measurements were made in,
    and the notes on the chosen factor."""
    chosen = parsed(resolution)
    factor, notes = scale_factor(rig, particles, chosen)
    built = coarse_grained(particles, factor)
    # the reduced values are bit for bit those of the whole run (stop_after_reduced); the speed by stress was
    # validated at the screening preset only (docs/lab.md), so a material's set-up keeps one speed; the packing
    # height is read as the rig's laboratory read it (a rig without a fill section is struck off at the brim)
    setup = lab_setup(chosen.mode, rig, shape_fractions(built), default_speed_factor=DEFAULT_SPEED_FACTOR,
                      scale_factor=factor, particles=built, stop_after_reduced=True,
                      fill_height_rule=rig.fill.height_rule if rig.fill is not None else "struck_off")
    return setup, notes


def setup_for(spec) -> Fidelity:
    """The lab set-up a job spec runs in: its preset (an old fidelity name) or its material's particles at its
    resolution in its rig. ``parameters.clump_aspect_ratio`` makes the mix's spheres two-sphere clumps in both."""
    from engine.lab.presets import fidelity  # the presets import this module
    from engine.lab.shape import elongated_shapes

    p = spec.parameters
    if is_preset(spec.resolution):
        return fidelity(spec.fidelity, p.particle_radius_m, p.clump_aspect_ratio)
    setup, _ = material_setup(spec.rig, spec.particles, spec.resolution)
    if p.clump_aspect_ratio != 1.0:
        setup = replace(setup, shapes=elongated_shapes(p.clump_aspect_ratio, setup.shapes), particles=None)
    return setup


def setup_notes(spec) -> list[str]:
    """What the job's set-up says about its resolution (the factor chosen, a target the standards cap)."""
    if is_preset(spec.resolution):
        return []
    setup, notes = material_setup(spec.rig, spec.particles, spec.resolution)
    if setup.scale_factor != 1.0:
        notes = [f"resolution: coarse, the material's particle sizes x {setup.scale_factor:.4g} in rig "
                 f"{setup.rig_name!r}"] + notes
    return notes


def particles_field(spec) -> str:
    """The spec field that sets the particles' sizes, which a refusal over the particle limit (or a gap they
    fall through) names: the screening spheres' radius, the preset, or the material's particles' resolution."""
    if is_preset(spec.resolution):
        if spec.fidelity == "screening":
            return "parameters.particle_radius_m"
        return "resolution" if spec.resolution is not None else "fidelity"
    return "resolution"


def incomparable(quantity, measured_rig: Rig | None, measured_particles: Particles | None,
                 setup: Fidelity) -> str | None:
    """Why a measured ``quantity`` (``engine.lab.registry.Quantity``) cannot be compared with what ``setup``
    simulates, or None. A value the apparatus sets (``Quantity.apparatus``) needs the job's rig to have the
    same sections as the rig it was measured in; a value that scales with the particles' size
    (``Quantity.per_particle``) needs the material's own particles as they are. Unknown (a material without a
    rig or particles): compared, as before rigs were data."""
    fixed = rig_value(quantity, setup)
    if fixed is not None:
        return fixed
    if measured_rig is not None and quantity.apparatus:
        differ = [name for name in quantity.apparatus if getattr(measured_rig, name) != getattr(setup.rig, name)]
        if differ:
            return (f"{quantity.name} is set by the apparatus ({' and '.join(differ)}): measured in rig "
                    f"{measured_rig.name!r}, simulated in rig {setup.rig_name!r}, where they differ; run at "
                    "resolution 'as_measured' or 'coarse' to simulate in the measurement's rig")
    if measured_particles is not None and quantity.per_particle and setup.particles != measured_particles:
        why = (f"coarse-grained x {setup.scale_factor:.4g}" if setup.scale_factor != 1.0
               else "not the material's particles")
        return f"{quantity.name} scales with the particles' size and the simulated particles are {why}"
    return None


def rig_value(quantity, setup: Fidelity) -> str | None:
    """Why ``quantity`` is the rig's own number in ``setup`` rather than the material's, or None: a packing
    struck off at a level (``Fill.height_rule`` "struck_off") has that level as its height, in the laboratory as
    in the simulation, so its packing height measures the apparatus, not the material."""
    if quantity.rig_value_when_struck_off and setup.fill_height_rule == "struck_off":
        return (f"{quantity.name} is the level the packing is struck off at ({setup.packing_height_m:g} m, rig "
                f"{setup.rig_name!r}): set by the apparatus, not by the material; the bulk density carries the "
                "fill's measurement")
    return None
