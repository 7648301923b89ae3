"""Where demcal and LIGGGHTS differ: the CCT on the same packings, removing one difference at a time.

    python3 bench/engine_difference.py                    # every step below, seeds 1 2 3
    python3 bench/engine_difference.py --steps exported no_tangential_dashpot --seeds 1 2 3 4 5
    python3 bench/engine_difference.py --json out.json

Issue 30, item 4. demcal's lab builds each packing (screening rig, thesis Table 4.9 set, 20 mm spheres,
linear law); both engines run the confined compression test on it (calibration.export.paired), so the
paired difference of E' carries the engines' and the lid's differences and not the packings' scatter.
Each step switches one more thing off in both engines:

    exported               the material as exported (verify_export's linear case)
    no_tangential_dashpot  damping_ratio_shear 0 for the CCT: the codes cap spring + dashpot differently
    no_wall_friction       and friction_pw 0 for the whole run (fill and CCT)
    frictionless           and friction_pp 0 for the CCT: normal springs and dashpots only

A clump material (``--params`` with ``clump_aspect_ratio``) runs the same way, LIGGGHTS moving demcal's bodies
with fix rigid (fix multisphere cannot start from a given packing; calibration/export/rig_liggghts.py).
``--liggghts-restart`` runs, for a clump material, LIGGGHTS' own fills instead: each packing's CCT under fix
multisphere as filled, then restarted from the same packing under fix rigid (calibration.export.paired.
liggghts_restart_cct), which tells LIGGGHTS' two rigid-body integrators apart:

    python3 bench/engine_difference.py --params clump.json --liggghts-restart --seeds 1 2 3 4 5 6

Needs Debian's ``liggghts``. Measured on the shared 2-core machine: 15-30 s per packing and step (the three CCTs,
2 cycles), about 40 s with 4 cycles; two-sphere clumps 275-445 s per packing (2 cycles, machine shared).
"""
from __future__ import annotations

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

# step -> (material changes for the whole run, contact changes for the CCT); each adds to the one before
STEPS = {
    "exported": ({}, {}),
    "no_tangential_dashpot": ({}, {"damping_ratio_shear": 0.0}),
    "no_wall_friction": ({"friction_pw": 0.0}, {"damping_ratio_shear": 0.0}),
    "frictionless": ({"friction_pw": 0.0}, {"damping_ratio_shear": 0.0, "friction_pp": 0.0}),
}


def main(argv: list[str] | None = None) -> int:
    from calibration.export.material import from_micro_parameters
    from calibration.export.paired import paired_cct
    from calibration.export.rig_liggghts import liggghts_executable
    from engine.lab.spec import MicroParameters

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", nargs="+", choices=list(STEPS), default=list(STEPS))
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--cycles", type=int, default=2)
    ap.add_argument("--speed-factor", type=float, default=None, help="lid speed = lab speed x this (default: the rig's)")
    ap.add_argument("--params", help="MicroParameters as JSON (screening spheres, or clumps with "
                                     "clump_aspect_ratio); default the thesis Table 4.9 set")
    ap.add_argument("--json", help="write the reports here")
    ap.add_argument("--liggghts-restart", action="store_true",
                    help="clumps: LIGGGHTS' own packings under fix multisphere, then restarted under fix rigid")
    args = ap.parse_args(argv)
    if liggghts_executable() is None:
        print("engine_difference: liggghts not found (apt-get install -y liggghts)", file=sys.stderr)
        return 2
    base = MicroParameters.model_validate(json.load(open(args.params))) if args.params else MicroParameters()
    if args.liggghts_restart:
        return _liggghts_restart(from_micro_parameters(base, "screening"), args)
    reports = []
    for step in args.steps:
        whole_run, cct = STEPS[step]
        params = base.model_copy(update=whole_run)
        material = from_micro_parameters(params, "screening")
        report = paired_cct(material, args.seeds, args.cycles, args.speed_factor, contact_changes=cct, label=step,
                            progress=lambda m: print(f"  [{step}] {m}", file=sys.stderr, flush=True))
        print(report.text(), flush=True)
        reports.append({"step": step, "whole_run": whole_run, **report.to_dict()})
    print("\nsummary: E' on the same packings, paired relative difference (mean +- standard error)")
    print(f"  {'step':24s} {'LIGGGHTS vs demcal restarted':>30s} {'demcal restarted vs kept':>26s} {'demcal kept, MPa':>17s}")
    for r in reports:
        lig, restart = r["differences"][0], r["differences"][1]
        print(f"  {r['step']:24s} {lig['mean'] * 100:+17.1f} % +- {lig['se'] * 100:4.1f} % "
              f"{restart['mean'] * 100:+13.1f} % +- {restart['se'] * 100:4.1f} % {restart['base_mean'] / 1e6:17.3f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(reports, fh, indent=1)
    return 0


def _liggghts_restart(material, args) -> int:
    from dataclasses import asdict

    from calibration.export.paired import liggghts_restart_cct

    if not material.particles.clumps:
        print("engine_difference: --liggghts-restart takes a clump material (--params with clump_aspect_ratio)",
              file=sys.stderr)
        return 2
    packings, diffs = liggghts_restart_cct(material, args.seeds, args.cycles, args.speed_factor,
                                           progress=lambda m: print(f"  {m}", file=sys.stderr, flush=True))
    print(f"LIGGGHTS' own clump packings: E' under fix multisphere (as filled) and fix rigid (restarted), "
          f"{args.cycles} cycles")
    for p in packings:
        print(f"  seed {p.seed}: {p.bodies} clumps  H {p.height_m * 1000:.1f} mm  E' multisphere "
              f"{p.modulus_multisphere_pa / 1e6:.3f}  rigid {p.modulus_rigid_restarted_pa / 1e6:.3f} MPa  "
              f"[{p.wall_time_s:.0f} s]")
    for d in diffs:
        print(f"  {d.quantity:58s} {d.base_mean:11.5g} -> {d.other_mean:11.5g}  {d.mean * 100:+6.1f} % +- "
              f"{d.se * 100:.1f} % (sd {d.sd * 100:.1f} %, n {d.n}){'  DIFFERS' if d.distinguishable else ''}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"packings": [asdict(p) for p in packings], "differences": [asdict(d) for d in diffs]}, fh,
                      indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
