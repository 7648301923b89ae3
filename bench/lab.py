"""Virtual-lab benchmark: wall time and particle-steps per second of each test, per fidelity.

    python3 bench/lab.py                  # screening fidelity, every test (a few minutes)
    python3 bench/lab.py --thesis         # also thesis fidelity (hours on one core)
    python3 bench/lab.py --tests fill cct --threads 1
    python3 bench/lab.py --battery        # the screening battery as one job (fill, CCT, DST x4), as the
                                          # service runs it, one thread: steps and wall time per stage,
                                          # then the 5,000-sphere pour of bench/engine_vs_liggghts.py at
                                          # one thread; last line: screening_battery_wall_s=X ...
                                          # battery_efficiency=Y (battery body-steps/s over the pour's)
    python3 bench/lab.py --battery --no-pour --options '{"stop_after_reduced": false, "dst_speed_by_stress": false}'
                                          # the battery as it ran before issue 34 (docs/lab.md)

Each test runs as the service runs it (a CCT job includes its fill, a DST job its fill and
precompression). Particle-steps count bodies (a clump is one particle); sphere-steps count its
spheres, which is what the contact search and force loop scale with.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))

POUR_SEED = 20260  # bench/engine_vs_liggghts.py's default seed: the pour measured there


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--thesis", action="store_true", help="also run thesis fidelity (very long)")
    ap.add_argument("--tests", nargs="+", default=["fill", "cct", "dst", "aor", "anchor"])
    ap.add_argument("--threads", type=int, default=None, help="numba threads (default: numba's)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--battery", action="store_true",
                    help="time the screening battery as one job (docs/examples/screening-battery.json), per stage, "
                         "and the 5,000-sphere pour at one thread for the battery's efficiency")
    ap.add_argument("--options", default=None, help="--battery: the job's options as JSON (TestOptions fields)")
    ap.add_argument("--no-pour", action="store_true", help="--battery: skip the pour (no battery_efficiency)")
    ap.add_argument("--job", default=None,
                    help="--battery: a job spec file (JSON, engine.lab.spec.JobSpec, e.g. a material's rig and "
                         "particles at a resolution) timed instead of the screening battery; --seed and --options "
                         "override its own")
    args = ap.parse_args(argv)
    if args.battery and not args.threads:
        args.threads = 1  # the service runs a screening battery per core, on one thread
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
    if args.battery:
        return battery(args)
    header = f"{'fidelity':<10} {'test':<7} {'wall s':>8} {'sim s':>7} {'steps':>9} {'bodies*steps/s':>15} {'spheres*steps/s':>16}"
    print(header)
    print("-" * len(header))
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


def print_stages(ctx) -> None:
    """The job's stages as the procedures named them (``RunContext.stages``), with each test's total."""
    header = f"{'stage':<34} {'steps':>8} {'sim s':>7} {'wall s':>7} {'body-steps/s':>13}"
    print(header)
    print("-" * len(header))
    totals: dict[str, list[float]] = {}

    def line(name, steps, sim_s, wall_s, body_steps):
        rate = body_steps / wall_s if wall_s > 0 else float("nan")
        print(f"{name:<34} {steps:8d} {sim_s:7.3f} {wall_s:7.2f} {rate:13.3e}")

    for name, st in ctx.stages.items():
        if st.steps == 0 and st.wall_time_s < 0.05:
            continue
        line(name, st.steps, st.simulated_time_s, st.wall_time_s, st.particle_steps)
        test = name.split(":")[0].split(" ")[0]
        t = totals.setdefault(test, [0, 0.0, 0.0, 0])
        for k, v in enumerate((st.steps, st.simulated_time_s, st.wall_time_s, st.particle_steps)):
            t[k] += v
    print("-" * len(header))
    for test, (steps, sim_s, wall_s, body_steps) in totals.items():
        line(f"{test} (all its stages)", int(steps), sim_s, wall_s, body_steps)


def pour_body_steps_per_s() -> tuple[float, float]:
    """One-thread throughput of bench/engine_vs_liggghts.py's 5,000-sphere pour (its FULL workload, its own
    process and measure: particle-steps over the stepping loop's wall seconds, all phases), and the same
    over its CPU seconds (what a shared host's other work does not inflate)."""
    sys.path.insert(0, str(HERE))
    import engine_vs_liggghts as pour

    res = pour.run_demcal(1, pour.FULL, POUR_SEED)
    pour.print_table("5,000-sphere pour (bench/engine_vs_liggghts.py), 1 thread", res)
    phases = res["phases"].values()
    per_cpu_s = sum(p["steps"] * p["atoms"] for p in phases) / sum(p["cpu_s"] for p in phases)
    return pour.throughput(res["phases"]), per_cpu_s


def battery(args) -> int:
    from engine.lab.battery import run_in_context
    from engine.lab.context import RunContext
    from engine.lab.spec import JobSpec

    options = json.loads(args.options) if args.options else {}
    if args.job:
        from pydantic import ValidationError

        try:
            with open(args.job) as fh:
                job = json.load(fh)
        except (OSError, ValueError) as exc:
            raise SystemExit(f"--job {args.job}: cannot read a JSON job spec ({exc})") from None
        if not isinstance(job, dict):
            raise SystemExit(f"--job {args.job}: a job spec is a JSON object")
        job.update(seed=args.seed, **({"options": {**job.get("options", {}), **options}} if options else {}))
        try:
            spec = JobSpec.model_validate(job)
        except ValidationError as exc:
            first = exc.errors(include_url=False)[0]
            where = ".".join(str(p) for p in first.get("loc", ()))
            raise SystemExit(f"--job {args.job}: {where}: {first.get('msg')}") from None
        what = f"job {args.job} ({spec.test})"
    else:
        spec = JobSpec(test="battery", fidelity="screening", seed=args.seed, options=options)
        what = "screening battery (fill, CCT, DST at four loads)"
    ctx = RunContext.from_spec(spec)
    t, cpu = time.perf_counter(), time.process_time()
    result = run_in_context(ctx)
    wall, cpu = time.perf_counter() - t, time.process_time() - cpu
    print(f"{what}, seed {args.seed}, options {spec.options.model_dump(exclude_defaults=True) or 'defaults'}")
    print_stages(ctx)
    rate = ctx.particle_steps / wall
    print(f"battery: {ctx.steps} steps, {ctx.simulated_time_s:.3f} s simulated, {wall:.1f} s wall, {rate:.3e} "
          f"body-steps/s; largest inertial number {result.provenance.max_inertial_number or float('nan'):.2e} "
          f"(speed factor {ctx.speed_factor:g}); load average {os.getloadavg()[0]:.2f}")
    for name, curve in result.curves.items():
        if name.startswith("dst_") and "inertial_number" in curve:
            i = sorted(curve["inertial_number"])
            print(f"{name} shearing: inertial number median {i[len(i) // 2]:.2e}, max {i[-1]:.2e} over "
                  f"{curve['shear_displacement_m'][-1] * 1000:.1f} mm of travel")
    for w in result.provenance.warnings:
        print(f"warning: {w}")
    tail = f"{'job' if args.job else 'screening_battery'}_wall_s={wall:.1f} battery_steps={ctx.steps}"
    if args.no_pour:
        print(tail)
        return 0
    sys.stdout.flush()
    pour_rate, pour_per_cpu_s = pour_body_steps_per_s()
    print(f"pour: {pour_rate:.3e} body-steps/s on one thread; load average {os.getloadavg()[0]:.2f}")
    # per CPU second as well: on a shared host the wall-clock ratio compares two differently crowded spells
    per_cpu_s = ctx.particle_steps / cpu
    print(f"per CPU second: battery {per_cpu_s:.3e}, pour {pour_per_cpu_s:.3e} body-steps, "
          f"ratio {per_cpu_s / pour_per_cpu_s:.3f}")
    print(f"{tail} battery_body_steps_per_s={rate:.4g} pour_body_steps_per_s={pour_rate:.4g} "
          f"battery_efficiency_cpu={per_cpu_s / pour_per_cpu_s:.3f} battery_efficiency={rate / pour_rate:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
