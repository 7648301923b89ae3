"""Angle of repose (thesis section 5.2): fill a bottomless bucket, lift it, measure the pile in eight sectors."""
from __future__ import annotations

import math

from engine.lab.bounds import SLOPE_ANGLE, Typical
from engine.lab.registry import Bench, LabTest, Quantity, Run, StageCost
from engine.lab.stops import AOR_MAX_LIFT_BUCKET_HEIGHTS, LEVEL_SETTLE_MAX_S, PILE_REST_MAX_S, RAIN_SETTLE_MAX_S


def _cost(ctx, planned: frozenset[str]) -> StageCost:
    from engine.lab.cost import packing_spheres

    preset, aor = ctx.preset, ctx.preset.aor
    bucket_h = aor.scale * aor.bucket_height_m
    r0, r1 = aor.scale * aor.bucket_bottom_radius_m, aor.scale * aor.bucket_top_radius_m
    bucket_m3 = math.pi * bucket_h / 3.0 * (r0**2 + r0 * r1 + r1**2)  # a frustum
    lift_speed = ctx.spec.options.aor_lift_speed_m_s or aor.lift_speed_m_s
    return StageCost(
        RAIN_SETTLE_MAX_S + LEVEL_SETTLE_MAX_S + AOR_MAX_LIFT_BUCKET_HEIGHTS * bucket_h / lift_speed + PILE_REST_MAX_S,
        "options.aor_lift_speed_m_s",
        packing_spheres(bucket_m3 * preset.expected_solid_fraction, preset.fill_margin,
                        preset.aor_shapes or preset.shapes))


def _run(bench: Bench, lo: float, hi: float) -> Run:
    from engine.lab.procedures.repose import run_aor

    aor = run_aor(bench.ctx)
    props = [TEST.property("angle_of_repose_deg", aor.reduction.angle_of_repose_deg)]
    props += [TEST.property("angle_of_repose_deg", angle, sector=k + 1)
              for k, angle in enumerate(aor.reduction.sector_angles_deg)
              if not math.isnan(angle)]  # sectors without a measurable flank are left out
    return Run(aor, props, aor.curves)


TEST = LabTest(
    name="aor",
    title="Angle of repose: the pile left by a lifted bucket",
    # Typical: Carr's classes run from 25-30 deg (very free flowing) to above 55 deg (very cohesive); glass
    # beads pile at about 22 deg (Beakawi Al-Hashemi & Baghabra Al-Amoudi 2018).
    quantities=(Quantity("angle_of_repose_deg", "deg", SLOPE_ANGLE, conditions=("sector",),
                         description="mean of the sectors; with sector k (1..8), that sector's flank",
                         typical=Typical(15.0, 70.0, "the angles of repose of granular materials",
                                         "Beakawi Al-Hashemi & Baghabra Al-Amoudi 2018")),),
    options=("include_aor", "aor_lift_speed_m_s", "aor_bucket_friction", "aor_floor_friction"),
    procedure="engine.lab.procedures.repose:run_aor",
    reducer="engine.lab.reducers.repose:angle_of_repose",
    cost=_cost,
    run=_run,
    battery="include_aor",
    apparatus=("angle_of_repose",),
    progress_weight=0.35,
    description="A bottomless tapered bucket on a floor is filled, levelled and lifted; the pile at rest is "
                "measured in eight azimuthal sectors.",
)
