"""Confined compression test (thesis sections 3.4 and 4.6.2): N load-unload cycles of the lid, and on request an
unload-reload loop at given stresses after them (``unload_reload``)."""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.procedures.fill import FillOutcome, smallest_radius_m
from engine.lab.procedures.lid import LidRecord, hold_stress, load_to, precompress, unload, unload_slowly
from engine.lab.reducers.cct import CctReduction, UnloadReload, reduce_cct, reduce_unload_reload
from engine.lab.stops import LID_MAX_TRAVEL_FRACTION


@dataclass
class CctOutcome:
    reduction: CctReduction
    record: LidRecord
    strain: np.ndarray
    precompressed: dict  # checkpoint after cycle 1: the DST's starting point
    # empty unless options.cct_unload_reload_stresses_pa asked for it
    unload_reload: UnloadReload = field(default_factory=UnloadReload)


def run_cct(ctx: RunContext, fill: FillOutcome) -> CctOutcome:
    sim = labsim.restore(fill.checkpoint)
    height = fill.packing_height_m
    record = LidRecord()
    precompress(ctx, sim, height, smallest_radius_m(ctx.preset), record)
    precompressed = sim.checkpoint()
    loops = ctx.spec.options.cct_unload_reload_stresses_pa
    for cycle in range(2, ctx.cct_cycles + 1):
        load_to(ctx, sim, ctx.cct_max_stress_pa, ctx.lid_speed_m_s, record, cycle, f"cct: cycle {cycle} loading",
                height, LID_MAX_TRAVEL_FRACTION * height)
        if cycle == ctx.cct_cycles and ctx.stop_after_reduced and not loops:
            break  # the reducer reads loading branches only, and nothing starts from the CCT's last state
        unload(ctx, sim, ctx.lid_speed_m_s, record, cycle, f"cct: cycle {cycle} unloading", LID_MAX_TRAVEL_FRACTION * height)
    cycles_end = len(record.lid_z_m)
    z = np.asarray(record.lid_z_m)
    stress = np.asarray(record.normal_stress_pa)
    touching = np.nonzero(stress > 0)[0]
    z_contact = z[touching[0]] if touching.size else z[0]
    strain = (z_contact - z) / height
    reduction = reduce_cct(strain, stress, ctx.preset.container_area_m2, height,
                           window_stresses_pa=ctx.spec.options.cct_window_stresses_pa)
    moduli = UnloadReload()
    if loops:
        ranges = unload_reload(ctx, sim, height, record, ctx.cct_cycles + 1, loops, reduction.confined_modulus_pa)
        strain = np.concatenate([strain, (z_contact - np.asarray(record.lid_z_m[cycles_end:])) / height])
        moduli = reduce_unload_reload(strain, np.asarray(record.normal_stress_pa), loops, ranges)
    return CctOutcome(reduction, record, strain, precompressed, moduli)


def unload_reload(ctx: RunContext, sim, height_m: float, record: LidRecord, cycle: int, stresses_pa: list[float],
                  loading_modulus_pa: float) -> list[tuple[int, int]]:
    """After the cycles, from the unloaded packing: load at the test's speed to each stress in turn, hold it on
    the servo until the packing is at rest, then unload slowly by a tenth (``lid.unload_slowly``); the record's
    index range of each small unloading. The loading branch between them is the next stress's approach, as in an
    oedometer's unload-reload steps; the cycles' E' is reduced before, from the cycles alone.

    A stress the packing does not come to rest at on the servo ends the sequence there (warned): the unloading
    would start from a moving packing, and every later stress from one the servo has stirred, so none of them
    is a modulus at a fixed contact network. Seen on DEM (session 32): Hertz-Mindlin at E 4 GPa with friction
    1.0 at 30 kPa, the lid's stress running to 0.6 MPa, and the unloading that followed had nothing to unload.
    No value there rather than a wrong one; the battery's other results stand."""
    area = ctx.preset.container_area_m2
    bulk_density_kg_m3 = float(np.sum(sim.body_masses_kg())) / (area * height_m)
    impedance = float(np.sqrt(bulk_density_kg_m3 * loading_modulus_pa))
    ranges = []
    for target in stresses_pa:
        tag = f"cct: unload-reload at {target / 1000:.3g} kPa"
        load_to(ctx, sim, target, ctx.lid_speed_m_s, record, cycle, f"{tag}: loading", height_m,
                LID_MAX_TRAVEL_FRACTION * height_m)
        if not hold_stress(ctx, sim, target, ctx.lid_speed_m_s, f"{tag}: holding"):
            ctx.warn(f"{tag}: the packing did not come to rest on the servo; no unload-reload modulus at "
                     f"{', '.join(f'{s / 1000:.3g}' for s in stresses_pa[len(ranges):])} kPa")
            break
        ranges.append(unload_slowly(ctx, sim, impedance, loading_modulus_pa, height_m, record, cycle, f"{tag}: unloading"))
    return ranges


def precompressed_state(ctx: RunContext, fill: FillOutcome) -> dict:
    """The DST's preparation when no CCT ran before it: cycle 1 only."""
    sim = labsim.restore(fill.checkpoint)
    precompress(ctx, sim, fill.packing_height_m, smallest_radius_m(ctx.preset), LidRecord())
    return sim.checkpoint()
