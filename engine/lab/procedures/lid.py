"""Lid moves shared by the CCT and the DST preparation: lower onto the packing, load, unload."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.stops import LID_MAX_TRAVEL_FRACTION

# lid travel per control step; the stress overshoot at a turning point is k_b times this
LID_TRAVEL_PER_SAMPLE_M = 2e-5
LID_START_GAP_FRACTION = 0.05  # of the smallest radius, above the highest sphere top


@dataclass
class LidRecord:
    time_s: list[float] = field(default_factory=list)
    lid_z_m: list[float] = field(default_factory=list)
    normal_stress_pa: list[float] = field(default_factory=list)
    cycle: list[float] = field(default_factory=list)

    def add(self, sim, area_m2: float, cycle: int) -> float:
        stress = float(sim.wall_force("lid")[2]) / area_m2
        self.time_s.append(sim.time_s)
        self.lid_z_m.append(float(sim.wall_position("lid")[2]))
        self.normal_stress_pa.append(stress)
        self.cycle.append(float(cycle))
        return stress


def place_lid(sim, r_min_m: float) -> float:
    """Bring the parked lid just above the highest sphere (the thesis lowered it from 30 mm above
    at test speed; starting it a fraction of a radius above gives the same gentle first contact)."""
    top = float(np.max(labsim.sphere_tops_m(sim)))
    z_target = top + LID_START_GAP_FRACTION * r_min_m
    z_now = float(sim.wall_position("lid")[2])
    sim.translate_wall("lid", (0.0, 0.0, z_target - z_now))
    sim.set_wall_velocity("lid", (0.0, 0.0, 0.0))
    return z_target


def _chunk(sim, speed_m_s: float) -> int:
    return max(1, int(LID_TRAVEL_PER_SAMPLE_M / (speed_m_s * sim.timestep_s)))


def load_to(ctx: RunContext, sim, target_stress_pa: float, speed_m_s: float, record: LidRecord, cycle: int,
            phase: str, packing_height_m: float, max_travel_m: float) -> None:
    """Lower the lid at constant speed until the lid stress reaches the target."""
    area = ctx.preset.container_area_m2
    sim.set_wall_velocity("lid", (0.0, 0.0, -speed_m_s))
    chunk = _chunk(sim, speed_m_s)
    z0 = float(sim.wall_position("lid")[2])
    rho = ctx.spec.parameters.particle_density_kg_m3
    d = labsim.mean_diameter_m(sim)
    while True:
        labsim.advance(ctx, sim, chunk)
        stress = record.add(sim, area, cycle)
        travel = z0 - record.lid_z_m[-1]
        if stress >= 0.25 * target_stress_pa and stress > 0:
            # uniaxial strain rate v / H; pressure = the lid stress
            ctx.inertial_number(speed_m_s / packing_height_m * d / math.sqrt(stress / rho), "cct/lid loading")
        ctx.report(min(stress / target_stress_pa, 1.0), phase)
        if stress >= target_stress_pa:
            break
        if travel > max_travel_m:
            raise ValueError(f"{phase}: the lid travelled {travel * 1000:.0f} mm without reaching "
                             f"{target_stress_pa / 1000:.1f} kPa; is the packing there?")
    sim.set_wall_velocity("lid", (0.0, 0.0, 0.0))


def unload(ctx: RunContext, sim, speed_m_s: float, record: LidRecord, cycle: int, phase: str,
           max_travel_m: float) -> None:
    """Raise the lid at constant speed until its force is zero."""
    area = ctx.preset.container_area_m2
    sim.set_wall_velocity("lid", (0.0, 0.0, speed_m_s))
    chunk = _chunk(sim, speed_m_s)
    z0 = float(sim.wall_position("lid")[2])
    start_stress = max(record.normal_stress_pa[-1] if record.normal_stress_pa else 1.0, 1e-9)
    while True:
        labsim.advance(ctx, sim, chunk)
        stress = record.add(sim, area, cycle)
        ctx.report(1.0 - max(stress, 0.0) / start_stress, phase)
        if stress <= 0.0 or record.lid_z_m[-1] - z0 > max_travel_m:
            break
    sim.set_wall_velocity("lid", (0.0, 0.0, 0.0))


def precompress(ctx: RunContext, sim, packing_height_m: float, r_min_m: float, record: LidRecord) -> None:
    """First cycle: lid onto the packing, load to the maximum stress, unload to zero force.

    The CCT's first cycle and the DST's preparation (thesis 4.7.2) are this same sequence, so a
    battery runs it once: from the same state, a deterministic engine gives the same packing.
    """
    place_lid(sim, r_min_m)
    travel = LID_MAX_TRAVEL_FRACTION * packing_height_m
    load_to(ctx, sim, ctx.cct_max_stress_pa, ctx.lid_speed_m_s, record, 1, "cct: cycle 1 loading",
            packing_height_m, travel)
    unload(ctx, sim, ctx.lid_speed_m_s, record, 1, "cct: cycle 1 unloading", travel)
