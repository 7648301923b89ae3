"""Proof of the LIGGGHTS hand-over: export a material, run it in LIGGGHTS and in demcal's lab, compare.

    python3 bench/verify_export.py                      # thesis Table 4.9 parameters + EPSD2 mu_r 0.2
    python3 bench/verify_export.py --material card.json # an ExportMaterial (calibration/export/material.py)
    python3 bench/verify_export.py --params micro.json  # a lab job's MicroParameters (screening spheres)
    python3 bench/verify_export.py --seeds 1 2 3 --cycles 2 --json out.json --keep /tmp/lig

Runs the screening rig's fill and confined compression test, one packing per seed in each engine, one
engine at a time, and prints bulk density, porosity and E' (mean and per stress window) of both with
their differences, scatter and the verdict. Needs Debian's ``liggghts`` (apt-get install -y liggghts).
Wall time on the shared 2-core project machine: spheres ~1.7 min per seed (demcal ~45 s, LIGGGHTS ~45 s);
two-sphere clumps (--params with clump_aspect_ratio) LIGGGHTS ~2 min (at half demcal's step), demcal 21-68 s per seed.
"""
from __future__ import annotations

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

DEFAULT_EFFECTS = {"rolling_epsd2": {"rolling_friction": 0.2}}


def _load(path: str) -> dict:
    with open(path) as fh:
        if path.endswith((".yaml", ".yml")):
            import yaml

            return yaml.safe_load(fh)
        return json.load(fh)


def main(argv: list[str] | None = None) -> int:
    from calibration.export.material import ExportMaterial, from_micro_parameters
    from calibration.export.rig_liggghts import liggghts_executable
    from calibration.export.verify import verify_export
    from engine.lab.spec import MicroParameters

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    src = ap.add_mutually_exclusive_group()
    src.add_argument("--material", help="ExportMaterial as JSON/YAML")
    src.add_argument("--params", help="MicroParameters as JSON/YAML (screening fidelity)")
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--cycles", type=int, default=2, help="CCT cycles (E' is the mean of cycles 2..N)")
    ap.add_argument("--speed-factor", type=float, default=None)
    ap.add_argument("--json", help="write the report here")
    ap.add_argument("--keep", help="directory for LIGGGHTS work dirs (kept); default: a temp dir")
    args = ap.parse_args(argv)
    if liggghts_executable() is None:
        print("verify_export: liggghts not found (apt-get install -y liggghts)", file=sys.stderr)
        return 2
    try:
        if args.material:
            material = ExportMaterial.model_validate(_load(args.material))
        else:
            params = MicroParameters.model_validate(_load(args.params)) if args.params else \
                MicroParameters(effects=DEFAULT_EFFECTS)
            material = from_micro_parameters(params, "screening")
    except (OSError, ValueError) as exc:
        print(f"verify_export: {exc}".splitlines()[0], file=sys.stderr)
        return 2
    report = verify_export(material, args.seeds, args.cycles, args.speed_factor, args.keep,
                           progress=lambda m: print(f"  {m}", file=sys.stderr, flush=True))
    print(report.text())
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(report.to_dict(), fh, indent=1)
    return 0 if report.holds else 1


if __name__ == "__main__":
    raise SystemExit(main())
