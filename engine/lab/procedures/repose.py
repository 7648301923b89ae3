"""Angle of repose (thesis section 5.2): a bottomless tapered bucket on a floor is filled, levelled,
and lifted at constant speed; the pile at rest is measured in eight azimuthal sectors."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.geometry import bucket_walls
from engine.lab.procedures.fill import largest_radius_m, level_and_measure, rain_packing
from engine.lab.reducers.repose import ReposeReduction, angle_of_repose
from engine.lab.stops import AOR_MAX_LIFT_BUCKET_HEIGHTS, PILE_REST_MAX_S, RAIN_SETTLE_MAX_S


@dataclass
class AorOutcome:
    reduction: ReposeReduction
    curves: dict


def run_aor(ctx: RunContext) -> AorOutcome:
    preset, params, opts = ctx.preset, ctx.spec.parameters, ctx.spec.options
    aor = preset.aor
    lift_speed = opts.aor_lift_speed_m_s or aor.lift_speed_m_s
    mu_bucket = aor.bucket_friction if opts.aor_bucket_friction is None else opts.aor_bucket_friction
    mu_floor = aor.floor_friction if opts.aor_floor_friction is None else opts.aor_floor_friction
    if aor.scale != 1.0:
        aor = replace(aor, bucket_bottom_radius_m=aor.scale * aor.bucket_bottom_radius_m,
                      bucket_top_radius_m=aor.scale * aor.bucket_top_radius_m,
                      bucket_height_m=aor.scale * aor.bucket_height_m, fill_height_m=aor.scale * aor.fill_height_m,
                      scale=1.0)
    if aor.wide_end_down:  # the frustum's radii as they stand on the floor: wide rim at the bottom
        aor = replace(aor, bucket_bottom_radius_m=aor.bucket_top_radius_m,
                      bucket_top_radius_m=aor.bucket_bottom_radius_m)
    shapes = preset.aor_shapes
    r0, r1, h = aor.bucket_bottom_radius_m, aor.bucket_top_radius_m, aor.bucket_height_m
    fill_height = min(aor.fill_height_m, h)
    r_fill = r0 + (r1 - r0) * fill_height / h
    volume = math.pi * fill_height / 3.0 * (r0**2 + r0 * r_fill + r_fill**2)
    r_max = largest_radius_m(preset, shapes)
    ctx.report(0.0, "aor: generating particles")
    # rain inside the narrower end, so that no body starts outside the walls
    packing, column_top = rain_packing(preset, ctx.spec.seed + 1, volume, min(r0, r1), shapes=shapes,
                                       column_solid_fraction=0.12)  # narrow column: wall-excluded volume
    sim = labsim.new_simulation(params, bucket_walls(aor, column_top + 2 * r_max, params.wall_stiffness_n_per_m,
                                                     mu_bucket, mu_floor), packing)
    labsim.settle(ctx, sim, "aor: filling the bucket", threshold=1e-4, min_time_s=0.2, max_time_s=RAIN_SETTLE_MAX_S)
    level_and_measure(ctx, sim, fill_height, "aor: levelling")

    chunk = labsim.steps_for(sim, 0.02)
    for name in ("bucket", "bucket_extension"):
        sim.set_wall_velocity(name, (0.0, 0.0, lift_speed))
    z_start = float(sim.wall_position("bucket")[2])
    lift_time, lift_z = [], []
    while True:
        labsim.advance(ctx, sim, chunk)
        z_rim = float(sim.wall_position("bucket")[2])
        lift_time.append(sim.time_s)
        lift_z.append(z_rim - z_start)
        ctx.report(0.1 + 0.8 * min((z_rim - z_start) / h, 1.0), "aor: lifting the bucket")
        if z_rim > float(np.max(labsim.sphere_tops_m(sim))) + 0.5 * r_max:
            break
        if z_rim - z_start > AOR_MAX_LIFT_BUCKET_HEIGHTS * h:  # a plug wedged in the bucket rides up with it: no pile to measure
            ctx.warn("aor: grains still above the bucket rim after lifting it three bucket heights (jammed in "
                     "the bucket); the angle is read from a pile that is not all on the floor")
            break
    for name in ("bucket", "bucket_extension"):
        sim.set_wall_velocity(name, (0.0, 0.0, 0.0))
    labsim.settle(ctx, sim, "aor: pile coming to rest", min_time_s=0.1, max_time_s=PILE_REST_MAX_S)
    red = angle_of_repose(sim.sphere_positions_m(), sim.sphere_radii_m(), centre_xy_m=(0.0, 0.0), floor_z_m=0.0,
                          sectors=8, bin_width_m=2.0 * float(np.mean(sim.sphere_radii_m())),
                          toe_height_m=1.5 * labsim.mean_diameter_m(sim))
    curves = {"aor_lift": {"time_s": lift_time, "bucket_rise_m": lift_z}}
    for k, (rr, hh) in enumerate(zip(red.profile_radius_m, red.profile_height_m)):
        curves[f"aor_profile_{k + 1}"] = {"radius_m": rr, "surface_height_m": hh}
    return AorOutcome(red, curves)
