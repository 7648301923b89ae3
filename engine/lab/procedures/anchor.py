"""Anchor pull-out (thesis section 5.3): a vertical tube with a foot plate stands in a bin filled to
height L; it accelerates linearly over 1 s to the pull speed and is pulled while its force is recorded."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.geometry import ANCHOR, anchor_bin_walls
from engine.lab.procedures.fill import COLUMN_SOLID_FRACTION, largest_radius_m, level_and_measure, shape_mix
from engine.lab.reducers.anchor import AnchorReduction, reduce_anchor
from engine.lab.stops import RAIN_SETTLE_MAX_S
from engine.particles.generation import BoxRegion, Packing, generate

FLOOR_GAP_M = 0.001  # the plate stands just clear of the bin floor


@dataclass
class AnchorOutcome:
    reduction: AnchorReduction
    curve: dict
    packing_height_m: float
    pull_speed_m_s: float


def _outside_boxes(packing: Packing, boxes) -> np.ndarray:
    """Bodies none of whose spheres touches any (centre, half extents) box."""
    centres, radii, body = packing.sphere_positions()
    hit = np.zeros(packing.n_bodies, bool)
    for centre, half in boxes:
        q = np.maximum(np.abs(centres - np.asarray(centre)) - np.asarray(half), 0.0)
        hit[body[np.linalg.norm(q, axis=1) < radii]] = True
    return ~hit


def run_anchor(ctx: RunContext) -> AnchorOutcome:
    preset, params, opts = ctx.preset, ctx.spec.parameters, ctx.spec.options
    a = preset.anchor
    height = opts.anchor_packing_height_m or a.packing_height_m
    speed = opts.anchor_pull_speed_m_s or a.pull_speed_m_s
    width = opts.anchor_bin_width_m or a.bin_width_m
    mu_anchor = a.anchor_friction if opts.anchor_friction is None else opts.anchor_friction
    distance = opts.anchor_pull_distance_m or a.pull_distance_m
    if a.plate_width_m >= width:
        raise ValueError("options.anchor_bin_width_m must exceed the 110 mm anchor plate")
    r_max = largest_radius_m(preset)
    solid = preset.fill_margin * preset.expected_solid_fraction * width**2 * height
    column_top = solid / (COLUMN_SOLID_FRACTION * width**2)
    half = 0.5 * width
    ctx.report(0.0, "anchor: generating particles")
    region = BoxRegion((-half, -half, 0.0), (half, half, column_top))
    packing = generate(shape_mix(preset), region, seed=ctx.spec.seed + 2, solid_volume_m3=solid)
    plate_half = (0.5 * a.plate_width_m, 0.5 * a.plate_width_m, 0.5 * a.plate_thickness_m)
    tube_half = (0.5 * a.tube_width_m, 0.5 * a.tube_width_m, 0.5 * a.tube_length_m)
    boxes = [((0, 0, FLOOR_GAP_M + plate_half[2]), plate_half),
             ((0, 0, FLOOR_GAP_M + a.plate_thickness_m + tube_half[2]), tube_half)]
    keep = _outside_boxes(packing, boxes)
    packing = Packing(packing.templates, packing.template_index[keep], packing.positions_m[keep],
                      packing.orientations[keep])
    walls = anchor_bin_walls(a, width, column_top + 2 * r_max, params.wall_stiffness_n_per_m, a.bin_friction,
                             mu_anchor, FLOOR_GAP_M)
    sim = labsim.new_simulation(params, walls, packing)
    labsim.settle(ctx, sim, "anchor: filling the bin", threshold=1e-4, min_time_s=0.2, max_time_s=RAIN_SETTLE_MAX_S)
    level_and_measure(ctx, sim, height, "anchor: levelling")

    for name in ANCHOR:
        sim.set_wall_velocity(name, (0.0, 0.0, speed), ramp_time_s=a.acceleration_time_s)
    z0 = float(sim.wall_position("anchor_plate")[2])
    chunk = labsim.steps_for(sim, 0.005)
    cols = {"time_s": [], "displacement_m": [], "pull_force_n": []}
    t0 = sim.time_s
    while True:
        labsim.advance(ctx, sim, chunk)
        disp = float(sim.wall_position("anchor_plate")[2]) - z0
        # the particles hold the anchor down: minus their vertical force on it is the pull resistance
        force = -sum(float(sim.wall_force(n)[2]) for n in ANCHOR)
        cols["time_s"].append(sim.time_s - t0)
        cols["displacement_m"].append(disp)
        cols["pull_force_n"].append(force)
        ctx.report(disp / distance, "anchor: pulling")
        if disp >= distance:
            break
    red = reduce_anchor(cols["displacement_m"], cols["pull_force_n"])
    return AnchorOutcome(red, cols, height, speed)
