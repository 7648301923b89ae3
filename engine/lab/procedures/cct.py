"""Confined compression test (thesis sections 3.4 and 4.6.2): N load-unload cycles of the lid."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.procedures.fill import FillOutcome, smallest_radius_m
from engine.lab.procedures.lid import LidRecord, load_to, precompress, unload
from engine.lab.reducers.cct import CctReduction, reduce_cct
from engine.lab.stops import LID_MAX_TRAVEL_FRACTION


@dataclass
class CctOutcome:
    reduction: CctReduction
    record: LidRecord
    strain: np.ndarray
    precompressed: dict  # checkpoint after cycle 1: the DST's starting point


def run_cct(ctx: RunContext, fill: FillOutcome) -> CctOutcome:
    sim = labsim.restore(fill.checkpoint)
    height = fill.packing_height_m
    record = LidRecord()
    precompress(ctx, sim, height, smallest_radius_m(ctx.preset), record)
    precompressed = sim.checkpoint()
    for cycle in range(2, ctx.cct_cycles + 1):
        load_to(ctx, sim, ctx.cct_max_stress_pa, ctx.lid_speed_m_s, record, cycle, f"cct: cycle {cycle} loading",
                height, LID_MAX_TRAVEL_FRACTION * height)
        if cycle == ctx.cct_cycles and ctx.stop_after_reduced:
            break  # the reducer reads loading branches only, and nothing starts from the CCT's last state
        unload(ctx, sim, ctx.lid_speed_m_s, record, cycle, f"cct: cycle {cycle} unloading", LID_MAX_TRAVEL_FRACTION * height)
    z = np.asarray(record.lid_z_m)
    stress = np.asarray(record.normal_stress_pa)
    touching = np.nonzero(stress > 0)[0]
    z_contact = z[touching[0]] if touching.size else z[0]
    strain = (z_contact - z) / height
    reduction = reduce_cct(strain, stress, ctx.preset.container_area_m2, height,
                           window_stresses_pa=ctx.spec.options.cct_window_stresses_pa)
    return CctOutcome(reduction, record, strain, precompressed)


def precompressed_state(ctx: RunContext, fill: FillOutcome) -> dict:
    """The DST's preparation when no CCT ran before it: cycle 1 only."""
    sim = labsim.restore(fill.checkpoint)
    precompress(ctx, sim, fill.packing_height_m, smallest_radius_m(ctx.preset), LidRecord())
    return sim.checkpoint()
