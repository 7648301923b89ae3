"""Anchor pull-out (thesis section 5.3): pull a plate anchor out of a filled bin and record the force."""
from __future__ import annotations

from engine.lab.bounds import POSITIVE
from engine.lab.registry import Bench, LabTest, Quantity, Run, StageCost
from engine.lab.stops import LEVEL_SETTLE_MAX_S, RAIN_SETTLE_MAX_S


def _cost(ctx, planned: frozenset[str]) -> StageCost:
    from engine.lab.cost import packing_spheres

    preset, opts, a = ctx.preset, ctx.spec.options, ctx.preset.anchor
    width = opts.anchor_bin_width_m or a.bin_width_m
    height = opts.anchor_packing_height_m or a.packing_height_m
    speed = opts.anchor_pull_speed_m_s or a.pull_speed_m_s
    pull_s = a.acceleration_time_s + (opts.anchor_pull_distance_m or a.pull_distance_m) / speed
    return StageCost(RAIN_SETTLE_MAX_S + LEVEL_SETTLE_MAX_S + pull_s, "options.anchor_pull_speed_m_s",
                     packing_spheres(width**2 * height * preset.expected_solid_fraction, preset.fill_margin,
                                     preset.shapes),
                     "options.anchor_bin_width_m")


def _run(bench: Bench, lo: float, hi: float) -> Run:
    from engine.lab.procedures.anchor import run_anchor

    anchor = run_anchor(bench.ctx)
    prop = TEST.property("peak_pull_force_n", anchor.reduction.peak_pull_force_n,
                         packing_height_m=anchor.packing_height_m, pull_speed_m_s=anchor.pull_speed_m_s)
    return Run(anchor, [prop], {"anchor": anchor.curve})


TEST = LabTest(
    name="anchor",
    title="Anchor pull-out: peak pull force",
    quantities=(Quantity("peak_pull_force_n", "N", POSITIVE, conditions=("packing_height_m", "pull_speed_m_s"),
                         apparatus=("anchor",)),),
    options=("include_anchor", "anchor_packing_height_m", "anchor_pull_speed_m_s", "anchor_friction",
             "anchor_bin_width_m", "anchor_pull_distance_m"),
    procedure="engine.lab.procedures.anchor:run_anchor",
    reducer="engine.lab.reducers.anchor:reduce_anchor",
    cost=_cost,
    run=_run,
    battery="include_anchor",
    apparatus=("anchor",),
    progress_weight=0.35,
    description="A tube with a foot plate in a bin filled to height L accelerates to the pull speed and is pulled "
                "while its force is recorded.",
)
