"""Lid moves shared by the CCT and the DST preparation: lower onto the packing, load, unload."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from engine.config import ServoSpec
from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.stops import DST_STABILISE_MAX_S, LID_MAX_TRAVEL_FRACTION, UNLOAD_RELOAD_MAX_S

# lid travel per control step; the stress overshoot at a turning point is k_b times this
LID_TRAVEL_PER_SAMPLE_M = 2e-5
LID_START_GAP_FRACTION = 0.05  # of the smallest radius, above the highest sphere top
# The unload-reload of the CCT (options.cct_unload_reload_stresses_pa): the small unloading's amplitude as a
# fraction of the held stress, small enough that few contacts slide (the branch is the packing's elastic
# response) and large enough to span tens of samples.
UNLOAD_RELOAD_FRACTION = 0.1
# Reversing the lid at speed v sends a stress jump of about 2 rho_b c v = 2 sqrt(rho_b E) v into the packing
# (the bulk's acoustic impedance; at the screening lid speed of 40 mm/s about 8 kPa, near the whole amplitude
# at 10 kPa). The small unloading runs slowly enough that the jump is this fraction of its amplitude; the
# reducer also skips the first part of the drop (engine.lab.reducers.cct.unload_reload_modulus).
UNLOAD_RELOAD_JUMP_FRACTION = 0.1
# Samples over the unloading's expected travel (expected from the loading E', which is 2-3 x softer than the
# unloading's, so the record holds fewer: tens)
UNLOAD_RELOAD_SAMPLES = 100


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


# The engine's servo closes this fraction of the force error per step through the lid contacts' springs and
# dashpots together (engine.stepping.move_walls). 0.38 is what the lab's lid had before the dashpots entered the
# servo (0.02 of the error through the springs alone, with the screening contacts' dashpot ratio c / (k dt) ~ 18:
# 0.02 x (1 + 18)), so linear contacts see the same lid; on Hertzian contacts at small forces the ratio grows
# past 49.5 and that lid chattered (the servo's instability seen on DEM, tests/engine/test_servo.py).
SERVO_GAIN = 0.38


def stabilise(ctx: RunContext, sim, target_pa: float, phase: str, min_time_s=0.05, max_time_s=DST_STABILISE_MAX_S) -> bool:
    """Hold the servo until the stress is within 2 % of the target and the packing is nearly at rest
    (kinetic energy ratio 1e-4: mean speed ~9 mm/s for 40 mm grains, a fraction of the shear speed).
    False when ``max_time_s`` passed first (warned): the caller decides whether what follows can be read."""
    area = ctx.preset.container_area_m2
    d = labsim.mean_diameter_m(sim)
    chunk = labsim.steps_for(sim, 0.01)
    t0 = sim.time_s
    while True:
        labsim.advance(ctx, sim, chunk)
        stress = float(sim.wall_force("lid")[2]) / area
        elapsed = sim.time_s - t0
        ctx.report(elapsed / max_time_s, phase)
        if elapsed >= min_time_s and abs(stress - target_pa) < 0.02 * target_pa \
                and labsim.kinetic_energy_ratio(sim, d) < 1e-4:
            return True
        if elapsed >= max_time_s:
            ctx.warn(f"{phase}: not stable after {max_time_s} s (stress {stress / 1000:.2f} kPa)")
            return False


def hold_stress(ctx: RunContext, sim, target_pa: float, max_speed_m_s: float, phase: str) -> bool:
    """The lid on its servo at ``target_pa`` until the packing is stable (``stabilise``), then stopped there;
    False when it did not come to rest there."""
    sim.set_wall_servo("lid", ServoSpec(axis=(0.0, 0.0, -1.0), target_stress_pa=target_pa,
                                        area_m2=ctx.preset.container_area_m2, max_speed_m_s=max_speed_m_s,
                                        gain_fraction=SERVO_GAIN))
    stable = stabilise(ctx, sim, target_pa, phase)
    sim.set_wall_velocity("lid", (0.0, 0.0, 0.0))
    return stable


def unload_slowly(ctx: RunContext, sim, bulk_impedance_pa_s_m: float, expected_modulus_pa: float,
                  packing_height_m: float, record: LidRecord, cycle: int, phase: str) -> tuple[int, int]:
    """Raise the lid until the stress has fallen by UNLOAD_RELOAD_FRACTION of its value, slowly (the speed whose
    reversal jump 2 Z v is UNLOAD_RELOAD_JUMP_FRACTION of that drop, Z = sqrt(rho_b E) the bulk's impedance).

    Returns the record's index range [start, end) of the unloading, its first sample the stress it starts from.
    ``expected_modulus_pa`` sets the sampling (UNLOAD_RELOAD_SAMPLES over the travel it predicts)."""
    area = ctx.preset.container_area_m2
    start = len(record.lid_z_m)
    top = record.add(sim, area, cycle)
    if top <= 0.0:  # the lid carries nothing: no unloading to read (the reducer gets one sample and says NaN)
        ctx.warn(f"{phase}: the lid carries no load ({top / 1000:.3g} kPa), nothing to unload")
        return start, len(record.lid_z_m)
    drop = UNLOAD_RELOAD_FRACTION * top
    speed = min(UNLOAD_RELOAD_JUMP_FRACTION * drop / (2.0 * bulk_impedance_pa_s_m), ctx.lid_speed_m_s)
    travel = drop / expected_modulus_pa * packing_height_m
    chunk = max(1, int(travel / UNLOAD_RELOAD_SAMPLES / (speed * sim.timestep_s)))
    sim.set_wall_velocity("lid", (0.0, 0.0, speed))
    t0 = sim.time_s
    while True:
        labsim.advance(ctx, sim, chunk)
        stress = record.add(sim, area, cycle)
        ctx.report(min((top - stress) / drop, 1.0), phase)
        if stress <= top - drop:
            break
        if sim.time_s - t0 > UNLOAD_RELOAD_MAX_S:
            ctx.warn(f"{phase}: the stress fell {(top - stress) / 1000:.3g} of {drop / 1000:.3g} kPa in "
                     f"{UNLOAD_RELOAD_MAX_S} s; the unload-reload modulus is read from what was recorded")
            break
    sim.set_wall_velocity("lid", (0.0, 0.0, 0.0))
    return start, len(record.lid_z_m)


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
