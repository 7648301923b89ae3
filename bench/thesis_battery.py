"""Run the battery at thesis fidelity with Table 4.9's parameters, saving each stage as it finishes.

Hours on one core (see docs/thesis-comparison.md), so it writes a JSON after every stage and can
be stopped at any time:

    nohup timeout 3h python3 bench/thesis_battery.py --out /tmp/thesis.json > /tmp/thesis.log 2>&1 &
"""
from __future__ import annotations

import argparse
import json
import time

from engine.lab.context import RunContext
from engine.lab.procedures.cct import precompressed_state, run_cct
from engine.lab.procedures.dst import run_one
from engine.lab.reducers.dst import mohr_coulomb_fit
from engine.lab.spec import JobSpec


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--speed-factor", type=float, default=None)
    ap.add_argument("--cycles", type=int, default=None)
    args = ap.parse_args()
    spec = JobSpec(test="battery", fidelity="thesis", seed=args.seed,
                   options={"speed_factor": args.speed_factor, "cct_cycles": args.cycles})
    started = time.perf_counter()
    out: dict = {"spec": spec.model_dump(), "stages": {}}

    def stage(name, ctx, **values):
        out["stages"][name] = {"wall_time_s": time.perf_counter() - started, "steps": ctx.steps,
                               "particle_steps": ctx.particle_steps, "simulated_time_s": ctx.simulated_time_s,
                               "max_inertial_number": ctx.max_inertial_number, "warnings": list(ctx.warnings),
                               **values}
        with open(args.out, "w") as fh:
            json.dump(out, fh, indent=1)
        print(f"[{time.perf_counter() - started:8.0f} s] {name}: {values}", flush=True)

    from engine.lab.procedures.fill import run_fill

    ctx = RunContext.from_spec(spec, progress=lambda f, p: None)
    fill = run_fill(ctx)
    stage("fill", ctx, **fill.properties)
    cct = run_cct(ctx, fill)
    stage("cct", ctx, confined_modulus_pa=cct.reduction.confined_modulus_pa,
          bulk_stiffness_n_per_m=cct.reduction.bulk_stiffness_n_per_m,
          modulus_per_cycle_pa=cct.reduction.modulus_per_cycle_pa,
          window_stress_mid_pa=cct.reduction.window_stress_mid_pa, window_modulus_pa=cct.reduction.window_modulus_pa)
    sig, tau = [], []
    for target in ctx.dst_normal_stresses_pa:
        run = run_one(ctx, cct.precompressed, fill.packing_height_m, target)
        sig.append(run.reduction.residual_normal_stress_pa)
        tau.append(run.reduction.residual_shear_stress_pa)
        extra = {}
        if len(sig) >= 2:
            fit = mohr_coulomb_fit(sig, tau)
            extra = {"friction_angle_deg": fit.friction_angle_deg, "cohesion_pa": fit.cohesion_pa, "r2": fit.r2}
        stage(f"dst_{target:.0f}", ctx, residual_normal_stress_pa=sig[-1], residual_shear_stress_pa=tau[-1],
              dilatancy_angle_deg=run.reduction.dilatancy_angle_deg, **extra)


if __name__ == "__main__":
    main()
