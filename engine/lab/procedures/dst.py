"""Direct shear test (thesis sections 3.3.2 and 4.7.2), one run per normal stress.

Per load, from the precompressed packing: reload to the target, hold it with the servo until the
packing is stable (stress within 2 %, at rest; the thesis waited 20 s), then move every bottom-half
wall in +x at the shear speed over the shear distance while the servo holds the normal stress.

A load the servo does not bring the lid to (its stabilising ends with the stress more than 10 % off) is
not sheared (warned): its residual shear stress and dilatancy would be read at another stress than the
one they are reported at, from a packing the servo is still driving. Seen on DEM (hertz_strong's second
design, session 33): at E 4 GPa six corners of eight missed some loads, one read 1.2 Pa of residual shear
at "52.4 kPa" with the lid's stress at zero and a dilatancy of -45 deg, and those values bent every
surface through the DST's targets. No value there rather than a wrong one, as the CCT's unload-reload
holds do (procedures.cct.unload_reload); the Mohr-Coulomb fit takes the loads that held, at least two.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from engine.config import ServoSpec
from engine.lab import sim as labsim
from engine.lab.context import RunContext
from engine.lab.geometry import BOTTOM_HALF
from engine.lab.procedures.lid import SERVO_GAIN, LidRecord, load_to, stabilise
from engine.lab.reducers.dst import (DstReduction, MohrCoulombFit, mohr_coulomb_fit, reduce_dst,
                                     samples_needed_past_window)
from engine.lab.stops import LID_MAX_TRAVEL_FRACTION

SAMPLES_PER_RUN = 800  # shear samples over the shear distance (the 8-10 % window gets ~150)
SHEAR_BAND_DIAMETERS = 10.0  # shear band thickness for the inertial number, in mean diameters
# A load whose stabilising ended with the lid's stress further than this from the target never reached it. The
# servo's own scatter while shearing packings that did settle: the residual window's normal stress was 0.94-1.14
# of the target in the middle 90 % of hertz_strong's 592 settled loads (session 34). A load at its stress whose
# packing was still moving a little is sheared (the stabilising's warning says so): the reduced form's 130 grains
# often miss the at-rest ratio in 0.5 s with the stress on target.
LOAD_NOT_REACHED_FRACTION = 0.10


@dataclass
class DstRun:
    normal_stress_target_pa: float
    reduction: DstReduction | None  # None: the load was not held, so not sheared
    curve: dict[str, list[float]]

    @property
    def held(self) -> bool:
        return self.reduction is not None


@dataclass
class DstOutcome:
    runs: list[DstRun]
    fit: MohrCoulombFit | None


def run_one(ctx: RunContext, precompressed: dict, packing_height_m: float, target_pa: float) -> DstRun:
    tag = f"dst {target_pa / 1000:.1f} kPa"
    sim = labsim.restore(precompressed)
    area = ctx.preset.container_area_m2
    scale = ctx.dst_speed_scale(target_pa)
    lid_speed = ctx.lid_speed_m_s * scale
    load_to(ctx, sim, target_pa, lid_speed, LidRecord(), 0, f"{tag}: reloading", packing_height_m,
            LID_MAX_TRAVEL_FRACTION * packing_height_m)
    v = ctx.shear_speed_m_s * scale
    sim.set_wall_servo("lid", ServoSpec(axis=(0.0, 0.0, -1.0), target_stress_pa=target_pa, area_m2=area,
                                        max_speed_m_s=max(v, lid_speed), gain_fraction=SERVO_GAIN))
    if not stabilise(ctx, sim, target_pa, f"{tag}: stabilising"):
        stress_pa = float(sim.wall_force("lid")[2]) / area
        if abs(stress_pa / target_pa - 1.0) > LOAD_NOT_REACHED_FRACTION:
            ctx.warn(f"{tag}: the servo did not bring the lid to this normal stress ({stress_pa / 1000:.3g} kPa); "
                     "not sheared, no residual shear stress or dilatancy at this load")
            return DstRun(target_pa, None, {})

    opts = ctx.spec.options
    distance = ctx.shear_distance_m
    # samples a fixed fraction of the shear distance apart, whatever stops the travel (so stopping early
    # leaves the record before the stop as it was)
    chunk = max(1, int(distance / SAMPLES_PER_RUN / (v * sim.timestep_s)))
    # the reducer reads the residual window and the smoothing's reach past it: once that is recorded, stop
    diameter, window_end_strain = ctx.preset.container_diameter_m, opts.residual_window_strain[1]
    samples_past_window = samples_needed_past_window(opts.moving_average_span) if ctx.stop_after_reduced else None
    x0 = float(sim.wall_position("floor")[0])
    z0 = float(sim.wall_position("lid")[2])
    rho = ctx.spec.parameters.particle_density_kg_m3
    d = labsim.mean_diameter_m(sim)
    band = min(SHEAR_BAND_DIAMETERS * d, packing_height_m)
    for name in BOTTOM_HALF:
        sim.set_wall_velocity(name, (v, 0.0, 0.0))
    cols = {k: [] for k in ("time_s", "shear_displacement_m", "shear_force_n", "normal_force_n", "lid_rise_m",
                            "inertial_number")}
    while True:
        labsim.advance(ctx, sim, chunk)
        disp = float(sim.wall_position("floor")[0]) - x0
        fs = -sum(float(sim.wall_force(n)[0]) for n in BOTTOM_HALF)
        fn = float(sim.wall_force("lid")[2])
        inertial = v / band * d / math.sqrt(max(fn / area, 1e-9) / rho)
        cols["time_s"].append(sim.time_s)
        cols["shear_displacement_m"].append(disp)
        cols["shear_force_n"].append(fs)
        cols["normal_force_n"].append(fn)
        cols["lid_rise_m"].append(float(sim.wall_position("lid")[2]) - z0)
        cols["inertial_number"].append(inertial)
        ctx.inertial_number(inertial, "dst/shearing")
        ctx.report(disp / distance, f"{tag}: shearing")
        if disp >= distance:
            break
        if samples_past_window is not None and disp / diameter > window_end_strain:
            samples_past_window -= 1
            if samples_past_window <= 0:
                break
    red = reduce_dst(cols["shear_displacement_m"], cols["shear_force_n"], cols["normal_force_n"],
                     cols["lid_rise_m"], area, ctx.preset.container_diameter_m,
                     window=tuple(opts.residual_window_strain), span=opts.moving_average_span)
    disp = np.asarray(cols["shear_displacement_m"])
    curve = {
        "time_s": cols["time_s"],
        "shear_displacement_m": cols["shear_displacement_m"],
        "shear_strain": (disp / ctx.preset.container_diameter_m).tolist(),
        "shear_stress_pa": (np.asarray(cols["shear_force_n"]) / area).tolist(),
        "normal_stress_pa": (np.asarray(cols["normal_force_n"]) / area).tolist(),
        "shear_stress_smoothed_pa": red.smoothed_shear_stress_pa.tolist(),
        "normal_stress_smoothed_pa": red.smoothed_normal_stress_pa.tolist(),
        "lid_rise_m": cols["lid_rise_m"],
        "inertial_number": cols["inertial_number"],
    }
    return DstRun(target_pa, red, curve)


def run_dst(ctx: RunContext, precompressed: dict, packing_height_m: float, lo: float, hi: float) -> DstOutcome:
    stresses = ctx.dst_normal_stresses_pa
    runs = []
    for k, target in enumerate(stresses):
        ctx.phase(lo + (hi - lo) * k / len(stresses), lo + (hi - lo) * (k + 1) / len(stresses))
        runs.append(run_one(ctx, precompressed, packing_height_m, target))
    held = [r for r in runs if r.held]
    fit = None
    if len(held) >= 2:
        fit = mohr_coulomb_fit([r.reduction.residual_normal_stress_pa for r in held],
                               [r.reduction.residual_shear_stress_pa for r in held])
    return DstOutcome(runs, fit)
