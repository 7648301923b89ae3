"""Run the battery at thesis fidelity with Table 4.9's parameters, saving each stage as it finishes.

About an hour on this 2-core machine (docs/thesis-comparison.md), so it writes the JSON after every
stage and can be stopped at any time. Fill and CCT run with every thread; the DST loads then run
``--jobs`` at a time in separate processes of one thread each (two one-thread runs do more work
than one two-thread run here):

    nohup python3 bench/thesis_battery.py --out /tmp/thesis.json --speed-factor 40 > /tmp/thesis.log 2>&1 &
"""
from __future__ import annotations

import argparse
import json
import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed

from engine.lab.context import RunContext
from engine.lab.spec import JobSpec


def _provenance(ctx: RunContext, wall_time_s: float) -> dict:
    return {"wall_time_s": wall_time_s, "steps": ctx.steps, "particle_steps": ctx.particle_steps,
            "simulated_time_s": ctx.simulated_time_s, "max_inertial_number": ctx.max_inertial_number,
            "warnings": list(ctx.warnings)}


def _dst_load(spec_json: str, precompressed: dict, packing_height_m: float, target_pa: float) -> dict:
    from engine.lab.procedures.dst import run_one

    ctx = RunContext.from_spec(JobSpec.model_validate_json(spec_json))
    run = run_one(ctx, precompressed, packing_height_m, target_pa)
    out = {"target_pa": target_pa, **_provenance(ctx, ctx.wall_time_s)}
    if run.held:  # a load the servo did not bring the lid to is not sheared (its warning says so)
        out.update(residual_normal_stress_pa=run.reduction.residual_normal_stress_pa,
                   residual_shear_stress_pa=run.reduction.residual_shear_stress_pa,
                   dilatancy_angle_deg=run.reduction.dilatancy_angle_deg)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--speed-factor", type=float, default=None)
    ap.add_argument("--cycles", type=int, default=None)
    ap.add_argument("--drop-height", type=float, default=None, help="fill_drop_height_m (m); unset: the preset's")
    ap.add_argument("--fill-friction", type=float, default=None,
                    help="fill_friction_pp: friction while the packing is prepared; unset: friction_pp")
    ap.add_argument("--fidelity", default="thesis", help="screening: a one-minute rehearsal of this script")
    ap.add_argument("--jobs", type=int, default=2, help="DST loads run at once, one thread each")
    args = ap.parse_args()
    spec = JobSpec(test="battery", fidelity=args.fidelity, seed=args.seed,
                   options={"speed_factor": args.speed_factor, "cct_cycles": args.cycles,
                            "fill_drop_height_m": args.drop_height, "fill_friction_pp": args.fill_friction})
    started = time.perf_counter()
    out: dict = {"spec": spec.model_dump(), "stages": {}}

    def save(name, values):
        out["stages"][name] = values
        with open(args.out, "w") as fh:
            json.dump(out, fh, indent=1)
        print(f"[{time.perf_counter() - started:8.0f} s] {name}: {values}", flush=True)

    from engine.lab.procedures.cct import run_cct
    from engine.lab.procedures.fill import run_fill
    from engine.lab.reducers.dst import mohr_coulomb_fit

    ctx = RunContext.from_spec(spec, progress=lambda f, p: None)
    ctx.validate()
    fill = run_fill(ctx)
    save("fill", {**_provenance(ctx, time.perf_counter() - started), **fill.properties})
    cct = run_cct(ctx, fill)
    save("cct", {**_provenance(ctx, time.perf_counter() - started), "confined_modulus_pa": cct.reduction.confined_modulus_pa,
                 "bulk_stiffness_n_per_m": cct.reduction.bulk_stiffness_n_per_m,
                 "modulus_per_cycle_pa": cct.reduction.modulus_per_cycle_pa,
                 "window_stress_mid_pa": cct.reduction.window_stress_mid_pa,
                 "window_modulus_pa": cct.reduction.window_modulus_pa})

    # children are fresh interpreters (spawn): they read the thread count when they import numba
    os.environ["NUMBA_NUM_THREADS"] = "1"
    done: dict[float, dict] = {}
    with ProcessPoolExecutor(max_workers=args.jobs, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = [pool.submit(_dst_load, spec.model_dump_json(), cct.precompressed, fill.packing_height_m, target)
                   for target in ctx.dst_normal_stresses_pa]
        for future in as_completed(futures):
            result = future.result()
            done[result["target_pa"]] = result
            save(f"dst_{result['target_pa']:.0f}", result)
    loads = [done[t] for t in sorted(done) if "residual_shear_stress_pa" in done[t]]
    if len(loads) < 2:
        raise SystemExit(f"{len(loads)} DST load(s) reached on the servo: no Mohr-Coulomb fit (see the loads' warnings)")
    fit = mohr_coulomb_fit([r["residual_normal_stress_pa"] for r in loads],
                           [r["residual_shear_stress_pa"] for r in loads])
    save("mohr_coulomb", {"wall_time_s": time.perf_counter() - started, "friction_angle_deg": fit.friction_angle_deg,
                          "cohesion_pa": fit.cohesion_pa, "r2": fit.r2})


if __name__ == "__main__":
    main()
