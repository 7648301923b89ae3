"""Tier-A acceptance of the missing-physics diagnosis: 300 fixed-seed hidden-effect cases.

Each case (calibration.testbed) hides 0, 1 or 2 effects in another world's closed-form battery and
runs the whole loop of calibration/ (design, fits, optimum, confirmation, localisation, diagnosis,
add, accept). Prints one line per case, the acceptance table of the design note next to its
targets, and a last machine-readable line.

    python3 bench/diagnosis_tier_a.py                 # 300 cases + 50 per bin below lambda 30 + 40 per other-form kind
    python3 bench/diagnosis_tier_a.py --cases 60 --jobs 1
    python3 bench/diagnosis_tier_a.py --chaotic       # the same cases, no two runs sharing their scatter
"""
from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def _one(args):
    seed, kind, chaotic = args
    from calibration.testbed import make_case, run_case

    started = time.perf_counter()
    out = run_case(make_case(seed, kind), chaotic=chaotic)
    out["wall_s"] = time.perf_counter() - started
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", type=int, default=300)
    ap.add_argument("--per-weak-bin", type=int, default=50,
                    help="single effects drawn into each detectability bin below lambda 30 (LAMBDA_BINS)")
    ap.add_argument("--per-form-kind", type=int, default=40,
                    help="cases of each kind of another model form (FORM_KINDS: nulls with and without the "
                         "model-form discrepancy, strong single effects with it)")
    ap.add_argument("--chaotic", action="store_true",
                    help="each run's scatter drawn from its seed and parameters, as on the DEM engine, where one "
                         "seed's packings at two parameter sets share little of it (StandinEvaluator.chaotic)")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--json", help="write every case's outcome to this file")
    ap.add_argument("--from-json", help="print the table of outcomes written earlier by --json (no runs)")
    args = ap.parse_args(argv)
    from calibration.testbed import acceptance, case_kinds, machine_line, refit_line, table_text, top_probe_line

    if args.from_json:
        with open(args.from_json) as fh:
            outcomes = json.load(fh)
        rows = acceptance(outcomes)
        print(table_text(rows))
        print(refit_line(outcomes))
        print(top_probe_line(outcomes))
        print(machine_line(rows))
        return 0

    work = [(seed, kind, args.chaotic) for seed, kind in enumerate(case_kinds(args.cases, args.per_weak_bin,
                                                                           args.per_form_kind))]
    if not work:
        ap.error("no cases: give --cases, --per-weak-bin or --per-form-kind above 0")
    started = time.perf_counter()
    outcomes = []
    ctx = mp.get_context("spawn")
    with ctx.Pool(max(1, args.jobs)) as pool:
        for o in pool.imap(_one, work):
            outcomes.append(o)
            lam = ",".join(f"{k}:{v:.0f}" for k, v in o["detectability"].items())
            print(f"case {o['seed']:3d} {o['kind']:<6} lambda[{lam}] lof={'fires' if o['lof_fired'] else 'passes'} "
                  f"rank={o['ranking'][:2]} added={o['accepted']} rms {o['rms_before']:.2f}->{o['rms_after']:.2f} "
                  f"batteries={o['batteries']} {o['wall_s']:.1f}s", flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(outcomes, fh, indent=1, default=str)
    rows = acceptance(outcomes)
    print()
    print(f"{len(outcomes)} cases in {time.perf_counter() - started:.0f} s "
          f"({args.jobs} processes); batteries per case: median "
          f"{sorted(o['batteries'] for o in outcomes)[len(outcomes) // 2]}")
    print(table_text(rows))
    print(refit_line(outcomes))
    print(top_probe_line(outcomes))
    print(machine_line(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
