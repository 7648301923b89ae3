"""Fill the shear-box container by rainfall, settle, level, settle again (thesis section 4.5.4).

Why whole bodies are deleted by their centre of mass: the thesis deleted single spheres whose centre
lay above 330 mm, which for clumps leaves fragments (half a pyramid is not one of its shapes, and
its mass is no template's). Deleting whole bodies keeps every particle a valid shape; the centre-of-
mass rule removes a body straddling the level as often as it keeps one, so the solid volume below
the level is unbiased. H is then read as the rig's laboratory read it (``Fill.height_rule``): the level the
packing was struck off at, or, at the presets, as the thesis's DEM did, from the highest sphere top.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.geometry import lid_wall, shear_box_walls
from engine.lab.presets import Fidelity
from engine.lab.reducers.packing import PackingState, bulk_properties, read_packing_height_m
from engine.lab.stops import LEVEL_SETTLE_MAX_S, RAIN_SETTLE_MAX_S
from engine.particles.distributions import ConstantSize, ShapeComponent, ShapeMix, TruncatedGaussian
from engine.particles.generation import CylinderRegion, generate

# loose solid fraction of the rainfall column: random insertion stays quick well below the ~0.38
# jamming limit of random sequential addition, and the column stays short (little fall time)
COLUMN_SOLID_FRACTION = 0.22


def shape_mix(preset: Fidelity, shapes=None) -> ShapeMix:
    comps = []
    for s in shapes or preset.shapes:
        if s.template is not None and s.size is not None:  # a material's custom clump, scaled to each drawn size
            comps.append(ShapeComponent("custom", s.size, s.volume_fraction, custom=s.template))
            continue
        if s.template is not None and s.radius_min_m == s.radius_max_m:
            # one given body (e.g. engine/lab/shape.py's elongated grain), not scaled
            comps.append(ShapeComponent("custom", ConstantSize(float(max(s.template.sphere_radii_m))),
                                        s.volume_fraction, custom=s.template))
            continue
        if s.template is not None:
            # a given body scaled to sphere radii spread over the fraction's range (elongated thesis spheres)
            comps.append(ShapeComponent("custom", TruncatedGaussian(s.radius_min_m, s.radius_max_m),
                                        s.volume_fraction, custom=s.template))
            continue
        if s.size is not None:  # a material's own distribution (a sieve curve, uniform sizes)
            size = s.size
        else:
            size = ConstantSize(s.radius_min_m) if s.radius_min_m == s.radius_max_m else \
                TruncatedGaussian(s.radius_min_m, s.radius_max_m)
        comps.append(ShapeComponent(s.shape, size, s.volume_fraction, overlap_factor=s.overlap_factor))
    return ShapeMix(tuple(comps))


def smallest_radius_m(preset: Fidelity, shapes=None) -> float:
    return min(s.radius_min_m for s in shapes or preset.shapes)


def largest_radius_m(preset: Fidelity, shapes=None) -> float:
    return max(s.radius_max_m for s in shapes or preset.shapes)


def rain_packing(preset: Fidelity, seed: int, bulk_volume_m3: float, region_radius_m: float,
                 z_floor_m: float = 0.0, shapes=None, column_solid_fraction: float = COLUMN_SOLID_FRACTION):
    """Bodies for ``fill_margin`` x the expected solid volume, at random in a loose column."""
    solid = preset.fill_margin * preset.expected_solid_fraction * bulk_volume_m3
    height = solid / (column_solid_fraction * np.pi * region_radius_m**2)
    region = CylinderRegion(region_radius_m, z_floor_m, z_floor_m + height)
    return generate(shape_mix(preset, shapes), region, seed=seed, solid_volume_m3=solid), z_floor_m + height


def drop_velocities_m_s(n_bodies: int, drop_height_m: float) -> np.ndarray:
    """Free-fall velocity after ``drop_height_m``: in free fall the column moves as one, so starting it
    with this speed is the same as dropping it from that much higher (the thesis's 4.7 m column)."""
    velocities = np.zeros((n_bodies, 3))
    velocities[:, 2] = -np.sqrt(2.0 * labsim.GRAVITY_M_S2 * drop_height_m)
    return velocities


def level_and_measure(ctx: RunContext, sim, level_m: float, phase: str) -> None:
    """Delete the bodies whose centre of mass is above ``level_m``, then settle again."""
    above = sim.positions_m()[:, 2] > level_m
    if np.any(above):
        sim.remove_bodies(above)
    labsim.settle(ctx, sim, phase, min_time_s=0.02, max_time_s=LEVEL_SETTLE_MAX_S)


def solid_volume_m3(sim) -> float:
    """Solid volume net of the clump lens overlaps: body mass / particle density (template volumes are net)."""
    return float(np.sum(sim.body_masses_kg())) / sim.config.materials[0].density_kg_m3


@dataclass
class FillOutcome:
    checkpoint: dict
    properties: dict[str, float]
    packing_height_m: float
    curves: dict[str, dict[str, list[float]]] = field(default_factory=dict)


def run_fill(ctx: RunContext) -> FillOutcome:
    preset, params = ctx.preset, ctx.spec.parameters
    r_max = largest_radius_m(preset)
    bulk_volume = preset.container_area_m2 * preset.packing_height_m
    ctx.report(0.0, "fill: generating particles")
    packing, column_top = rain_packing(preset, ctx.spec.seed, bulk_volume, preset.container_radius_m)
    lid_parked_z = column_top + 2 * r_max
    walls = shear_box_walls(preset, lid_parked_z + 2 * r_max, params.wall_stiffness_n_per_m, params.friction_pw,
                            smallest_radius_m(preset), ring_width_m=ctx.shear_distance_m + 2.5 * r_max)
    # the lid exists from the start, parked above the column: adding a wall later would reset the
    # tangential history of every wall contact of the settled packing
    walls.append(lid_wall(preset, lid_parked_z, params.wall_stiffness_n_per_m, params.friction_pw))
    preparation_friction = ctx.spec.options.fill_friction_pp
    prep_params = params if preparation_friction is None else params.model_copy(
        update={"friction_pp": preparation_friction})
    sim = labsim.new_simulation(prep_params, walls, packing,
                                velocities_m_s=drop_velocities_m_s(packing.n_bodies, ctx.rain_drop_height_m))
    ctx.report(0.0, "fill: generating particles")  # charges the generation's wall time to its own phase
    record: list = []
    # the first settle only has to bring the heap near rest before levelling (ratio 1e-4); the
    # levelled packing then settles to the 1e-5 criterion
    labsim.settle(ctx, sim, "fill: rainfall and settling", threshold=1e-4, min_time_s=0.2, max_time_s=RAIN_SETTLE_MAX_S,
                  record=record)
    level_and_measure(ctx, sim, preset.packing_height_m, "fill: levelling")
    # what the lid meets (the CCT's and DST's strains): the highest sphere top as built
    height = float(np.max(labsim.sphere_tops_m(sim)))
    # the packing height as the rig's laboratory reads it: the level it was struck off at, or the thesis's DEM rule
    # with the radii at the material's own size (a coarse resolution's grains stand out of the levelled surface by
    # s times more; equal to ``height`` as measured)
    measured = read_packing_height_m(preset.fill_height_rule, preset.packing_height_m, sim.sphere_positions_m()[:, 2],
                                     sim.sphere_radii_m(), preset.scale_factor)
    props = bulk_properties(PackingState(solid_volume_m3(sim), params.particle_density_kg_m3, measured,
                                         preset.container_area_m2, sim.n_bodies))
    if preparation_friction is not None:
        # the packing keeps its structure; the tests that start from it see the calibrated friction
        sim.set_material(0, friction=params.friction_pp)
    curves = {"fill_settling": {"time_s": [t for t, _ in record], "kinetic_energy_ratio": [k for _, k in record]}}
    ctx.report(1.0, "fill: done")
    return FillOutcome(sim.checkpoint(), props, height, curves)
