"""Today's screening battery against the one with fewer steps: every reduced quantity over several seeds.

    python3 bench/battery_steps_check.py                       # seeds 1 2 3, one thread, ~6 batteries
    python3 bench/battery_steps_check.py --seeds 1 2 3 4 5 --out /tmp/check.json
    python3 bench/battery_steps_check.py --from-json /tmp/check.json   # reprint a saved run's table
    python3 bench/battery_steps_check.py --from-json a.json b.json --markdown   # two runs' seeds together

"old" is the battery as it ran before issue 34 (``OLD_OPTIONS``: the shear to the full shear distance, the
CCT's last unloading, one DST speed at every normal stress); "new" is the screening default (docs/lab.md,
Fewer steps per battery). Same micro parameters (the defaults) and the same seeds for both. For each
quantity the table gives the mean +- sample standard deviation over the seeds, old and new, and the
difference of the means in standard errors, (new - old) / sqrt(sd_old^2 / n + sd_new^2 / n): the
seed-to-seed scatter is what a change must stay within (|difference| <= 2 standard errors); "same bits"
says where every seed gave the very same float. The fill, the CCT and the lightest DST load are the same to
the bit (same seed; the new stop rules drop only records no reducer reads, and the lightest load keeps its
speed); the other DST rows carry the speed change.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

# the battery before issue 34, as options (the screening preset's old behaviour)
OLD_OPTIONS = {"stop_after_reduced": False, "dst_speed_by_stress": False}
NEW_OPTIONS: dict = {}  # the screening defaults
Z_LIMIT = 2.0


def run_battery(seed: int, options: dict) -> dict:
    from engine.lab.battery import run_in_context
    from engine.lab.context import RunContext
    from engine.lab.spec import JobSpec

    ctx = RunContext.from_spec(JobSpec(test="battery", fidelity="screening", seed=seed, options=options))
    t = time.perf_counter()
    result = run_in_context(ctx)
    wall = time.perf_counter() - t
    values = {}
    for p in result.properties:
        cond = ",".join(f"{k}={v:g}" for k, v in sorted(p.condition.items()))
        values[f"{p.test} {p.quantity}" + (f" [{cond}]" if cond else "")] = p.value
    return {"seed": seed, "steps": ctx.steps, "wall_s": wall, "body_steps": ctx.particle_steps,
            "max_inertial_number": result.provenance.max_inertial_number, "values": values,
            "warnings": result.provenance.warnings}


def _mean_sd(xs: list[float]) -> tuple[float, float]:
    n = len(xs)
    m = sum(xs) / n
    sd = math.sqrt(sum((x - m) ** 2 for x in xs) / (n - 1)) if n > 1 else float("nan")
    return m, sd


def difference_in_standard_errors(old: list[float], new: list[float]) -> float:
    """(mean new - mean old) / sqrt(sd_old^2 / n_old + sd_new^2 / n_new); 0 when both are identical."""
    (mo, so), (mn, sn) = _mean_sd(old), _mean_sd(new)
    se = math.sqrt(so ** 2 / len(old) + sn ** 2 / len(new))
    if se == 0:
        return 0.0 if mn == mo else math.copysign(math.inf, mn - mo)
    return (mn - mo) / se


def comparable(values: dict) -> dict:
    """The CCT's E' per equal stress window is keyed by the window's mid stress, a fifth of each run's own
    peak: rename those by window number (1 = lowest) so that seeds and settings line up."""
    prefix = "cct confined_modulus_pa [normal_stress_pa="
    windows = sorted((float(k[len(prefix):-1]), k) for k in values if k.startswith(prefix))
    out = {k: v for k, v in values.items() if not k.startswith(prefix)}
    for rank, (_, k) in enumerate(windows, 1):
        out[f"cct confined_modulus_pa [window {rank} of {len(windows)}]"] = values[k]
    return out


def print_markdown(runs: dict) -> None:
    """The table as docs/lab.md shows it."""
    old = [comparable(r["values"]) for r in runs["old"]]
    new = [comparable(r["values"]) for r in runs["new"]]
    print(f"| quantity | old mean +- sd | new mean +- sd | difference / SE | same bits |\n|---|---|---|---|---|")
    for k in [k for k in old[0] if all(k in v for v in old + new)]:
        o, n = [v[k] for v in old], [v[k] for v in new]
        (mo, so), (mn, sn) = _mean_sd(o), _mean_sd(n)
        same = "every seed" if o == n else "no"
        print(f"| {k} | {mo:.4g} +- {so:.2g} | {mn:.4g} +- {sn:.2g} | "
              f"{difference_in_standard_errors(o, n):+.2f} | {same} |")


def print_table(runs: dict) -> bool:
    old = [dict(r, values=comparable(r["values"])) for r in runs["old"]]
    new = [dict(r, values=comparable(r["values"])) for r in runs["new"]]
    names = [k for k in old[0]["values"] if all(k in r["values"] for r in old + new)]
    missing = sorted({k for r in old + new for k in r["values"]} - set(names))
    width = max(len(k) for k in names)
    print(f"\n{'quantity':<{width}} {'old mean +- sd':>24} {'new mean +- sd':>24} {'diff/SE':>8}  same bits")
    ok = True
    for k in names:
        o = [r["values"][k] for r in old]
        n = [r["values"][k] for r in new]
        (mo, so), (mn, sn) = _mean_sd(o), _mean_sd(n)
        z = difference_in_standard_errors(o, n)
        flag = "" if abs(z) <= Z_LIMIT else "  <-- beyond 2 SE"
        ok &= abs(z) <= Z_LIMIT
        same = "every seed" if o == n else "no"
        print(f"{k:<{width}} {mo:>12.5g} +- {so:<9.3g} {mn:>12.5g} +- {sn:<9.3g} {z:8.2f}  {same}{flag}")
    if missing:
        print(f"not in every run (left out): {', '.join(missing)}")
    print()
    print(f"{'seed':>6} {'steps old':>10} {'steps new':>10} {'new/old':>8} {'wall old s':>11} {'wall new s':>11} "
          f"{'max I old':>10} {'max I new':>10}")
    for o, n in zip(old, new):
        print(f"{o['seed']:>6} {o['steps']:>10} {n['steps']:>10} {n['steps'] / o['steps']:8.3f} {o['wall_s']:11.1f} "
              f"{n['wall_s']:11.1f} {o['max_inertial_number']:10.2e} {n['max_inertial_number']:10.2e}")
    so, sn = sum(r["steps"] for r in old) / len(old), sum(r["steps"] for r in new) / len(new)
    wo, wn = sum(r["wall_s"] for r in old) / len(old), sum(r["wall_s"] for r in new) / len(new)
    print(f"{'mean':>6} {so:>10.0f} {sn:>10.0f} {sn / so:8.3f} {wo:11.1f} {wn:11.1f}")
    for label, rs in (("old", old), ("new", new)):
        for r in rs:
            for w in r["warnings"]:
                print(f"warning ({label}, seed {r['seed']}): {w}")
    print(f"\nsteps_old={so:.0f} steps_new={sn:.0f} steps_ratio={sn / so:.3f} wall_ratio={wn / wo:.3f} "
          f"within_{Z_LIMIT:g}_se={'yes' if ok else 'no'}")
    return ok


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--out", default=None, help="save the runs as JSON")
    ap.add_argument("--from-json", nargs="+", default=None,
                    help="print the table of saved runs (several files: their seeds together), no simulation")
    ap.add_argument("--markdown", action="store_true", help="with --from-json: the table as markdown")
    args = ap.parse_args(argv)
    if args.from_json:
        runs = {"old": [], "new": []}
        for path in args.from_json:
            saved = json.load(open(path))
            runs["old"] += saved["old"]
            runs["new"] += saved["new"]
        if args.markdown:
            print_markdown(runs)
            return 0
        return 0 if print_table(runs) else 1
    if len(args.seeds) < 2:
        ap.error("give at least two seeds: the scatter needs them")
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")  # a screening battery runs on one thread anyway
    from engine.lab.battery import run_job
    from engine.lab.spec import JobSpec

    # compile (or load) the kernels first, so that the first battery's wall time is not the compiler's
    run_job(JobSpec(test="fill", parameters={"particle_radius_m": 0.05}))
    runs: dict[str, list] = {"old": [], "new": [], "old_options": OLD_OPTIONS, "new_options": NEW_OPTIONS}
    for seed in args.seeds:
        for label, options in (("old", OLD_OPTIONS), ("new", NEW_OPTIONS)):
            r = run_battery(seed, options)
            runs[label].append(r)
            print(f"seed {seed} {label}: {r['steps']} steps, {r['wall_s']:.1f} s, largest inertial number "
                  f"{r['max_inertial_number']:.2e}", flush=True)
            if args.out:
                Path(args.out).write_text(json.dumps(runs, indent=1))
    return 0 if print_table(runs) else 1


if __name__ == "__main__":
    sys.exit(main())
