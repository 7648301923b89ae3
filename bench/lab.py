"""Virtual-lab benchmark: wall time and particle-steps per second of each test, per fidelity.

    python3 bench/lab.py                  # screening fidelity, every test (a few minutes)
    python3 bench/lab.py --thesis         # also thesis fidelity (hours on one core)
    python3 bench/lab.py --tests fill cct --threads 1
    python3 bench/lab.py --battery        # the screening battery as one job (fill, CCT, DST x4), as the
                                          # service runs it; last line: screening_battery_wall_s=X

Each test runs as the service runs it (a CCT job includes its fill, a DST job its fill and
precompression). Particle-steps count bodies (a clump is one particle); sphere-steps count its
spheres, which is what the contact search and force loop scale with.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--thesis", action="store_true", help="also run thesis fidelity (very long)")
    ap.add_argument("--tests", nargs="+", default=["fill", "cct", "dst", "aor", "anchor"])
    ap.add_argument("--threads", type=int, default=None, help="numba threads (default: numba's)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--battery", action="store_true",
                    help="time the screening battery as one job (docs/examples/screening-battery.json)")
    args = ap.parse_args(argv)
    if args.threads:
        os.environ["NUMBA_NUM_THREADS"] = str(args.threads)
    import numba

    from engine.lab.battery import run_in_context
    from engine.lab.context import RunContext
    from engine.lab.spec import JobSpec

    # compile the kernels once so that the first test's time is not the compiler's
    t = time.perf_counter()
    run_in_context(RunContext.from_spec(JobSpec(test="fill", parameters={"particle_radius_m": 0.05})))
    print(f"warm-up (kernel compile or cache load + a tiny fill): {time.perf_counter() - t:.1f} s")
    print(f"numba threads: {numba.get_num_threads()}")
    header = f"{'fidelity':<10} {'test':<7} {'wall s':>8} {'sim s':>7} {'steps':>9} {'bodies*steps/s':>15} {'spheres*steps/s':>16}"
    print(header)
    print("-" * len(header))
    if args.battery:
        ctx = RunContext.from_spec(JobSpec(test="battery", fidelity="screening", seed=args.seed))
        t = time.perf_counter()
        run_in_context(ctx)
        wall = time.perf_counter() - t
        print(f"screening battery (fill, CCT, DST at four loads): {wall:.1f} s wall, {ctx.steps} steps, "
              f"{ctx.particle_steps / wall:.3e} body-steps/s; load average {os.getloadavg()[0]:.2f}")
        print(f"screening_battery_wall_s={wall:.1f}")
        return 0
    fidelities = ["screening"] + (["thesis"] if args.thesis else [])
    for fid in fidelities:
        for test in args.tests:
            opts = {"anchor_pull_distance_m": 0.05} if test == "anchor" else {}
            ctx = RunContext.from_spec(JobSpec(test=test, fidelity=fid, seed=args.seed, options=opts))
            t = time.perf_counter()
            run_in_context(ctx)
            wall = time.perf_counter() - t
            print(f"{fid:<10} {test:<7} {wall:8.1f} {ctx.simulated_time_s:7.2f} {ctx.steps:9d} "
                  f"{ctx.particle_steps / wall:15.3e} {ctx.sphere_steps / wall:16.3e}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
