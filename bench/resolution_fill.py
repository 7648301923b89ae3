"""Does a coarse resolution shift the packing? The fill of one material at several resolutions in its own rig.

A campaign at a coarse resolution compares the bulk mass, the packing height and the bulk density it simulates
with measurements made on the material's own grains in the same rig (issue 29: "no rig mismatch"). This runs
the fill of the material as measured and coarse-grained, at the same micro parameters and seeds, and prints per
resolution the mean and sample sd over the seeds of what the fill reports, then each coarse resolution's
difference from the first (as measured, by default) against the scatter of that difference, and against the
measurement's own standard uncertainty where the material has one. A difference within both is a resolution
that does not shift what is compared; one beyond them says what the coarse grains do to the packing.

    python3 bench/resolution_fill.py --founding-spheres --factors 1,1.3 --seeds 1,2,3 \\
        --parameters '{"particle_density_kg_m3": 2585, "particle_stiffness_n_per_m": 3e6, "friction_pp": 1.0, "friction_pw": 0.62}'
    python3 bench/resolution_fill.py --material my_material.json --factors 1,1.5,2

``--founding-spheres``: the bundled thesis aggregate as bench/founding_case.py models it (volume-equivalent
spheres) in its 590 mm box. ``--material FILE``: a material as ``POST /api/v1/materials`` takes it, with
``particles`` and a ``rig`` that is a bundled record's name or a whole rig record. One numba thread per fill.
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.dirname(HERE))

FILL_QUANTITIES = ("bulk_mass_kg", "packing_height_m", "bulk_density_kg_m3", "porosity")


def _material(args) -> dict:
    if args.founding_spheres:
        from founding_case import material_body

        with open(os.path.join(os.path.dirname(HERE), "service", "materials", "thesis_coarse_aggregate.json")) as fh:
            return material_body(json.load(fh), "founding case as spheres")
    with open(args.material) as fh:
        return json.load(fh)


def _rig(record) -> dict:
    from engine.lab.rigs import bundled_rig, rig_json

    return rig_json(bundled_rig(record)) if isinstance(record, str) else record


def _fill(material: dict, factor: float, seed: int, parameters: dict) -> dict[str, float]:
    from calibration.keys import responses_of
    from engine.lab import run_job
    from engine.lab.spec import JobSpec

    resolution = "as_measured" if factor == 1.0 else {"mode": "coarse", "scale_factor": factor}
    spec = JobSpec.model_validate({"test": "fill", "seed": seed, "resolution": resolution,
                                   "rig": _rig(material["rig"]), "particles": material["particles"],
                                   "parameters": parameters})
    result = run_job(spec)
    out = {r["quantity"]: r["value"] for r in responses_of(result).values() if r["test"] == "fill"}
    return out


def _stats(values: list[float]) -> tuple[float, float]:
    n = len(values)
    mean = sum(values) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1)) if n > 1 else math.nan
    return mean, sd


def _measured_sd(material: dict) -> dict[str, float]:
    """The standard uncertainty of each measured fill quantity's mean (sample sd over sqrt n), in SI: the
    measurements converted as the service converts them (``service.materials.schemas.MeasurementIn``)."""
    from service.materials.schemas import MeasurementIn

    out = {}
    for m in material.get("measurements") or []:
        if m.get("test") != "fill":
            continue
        values = [v for v in MeasurementIn.model_validate(m).to_si()["values"] if v is not None]
        if len(values) > 1:
            out[m["quantity"]] = _stats(values)[1] / math.sqrt(len(values))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    which = ap.add_mutually_exclusive_group(required=True)
    which.add_argument("--founding-spheres", action="store_true", help="the thesis aggregate as volume-equivalent spheres")
    which.add_argument("--material", help="a material JSON with particles and rig")
    ap.add_argument("--factors", default="1,1.3", help="comma-separated scale factors; 1 is as measured")
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--parameters", default="{}", help="micro parameters (JSON, SI)")
    args = ap.parse_args(argv)
    try:
        factors = [float(x) for x in args.factors.split(",")]
        seeds = [int(x) for x in args.seeds.split(",")]
        parameters = json.loads(args.parameters)
    except ValueError as exc:
        ap.error(f"--factors, --seeds or --parameters: {exc}")
    if any(not f >= 1.0 for f in factors):
        ap.error("--factors: each at least 1 (coarse-graining makes grains larger)")
    if len(seeds) < 2:
        ap.error("--seeds: at least two, for the scatter")
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    material = _material(args)
    measured_sd = _measured_sd(material)
    rows: dict[float, dict[str, list[float]]] = {}
    for factor in factors:
        for seed in seeds:
            started = time.monotonic()
            values = _fill(material, factor, seed, parameters)
            print(f"x{factor:g} seed {seed}: " + ", ".join(f"{q} {values[q]:.5g}" for q in FILL_QUANTITIES if q in values)
                  + f" ({time.monotonic() - started:.0f} s)", flush=True)
            for q, v in values.items():
                rows.setdefault(factor, {}).setdefault(q, []).append(float(v))
    base = factors[0]
    figures = {}
    for factor in factors:
        for q in FILL_QUANTITIES:
            if q not in rows[factor]:
                continue
            mean, sd = _stats(rows[factor][q])
            line = f"x{factor:g} {q}: mean {mean:.5g}, sd {sd:.3g} over {len(seeds)} seeds"
            if factor != base:
                b_mean, b_sd = _stats(rows[base][q])
                diff = mean - b_mean
                scatter = math.sqrt((sd ** 2 + b_sd ** 2) / len(seeds))
                line += (f"; against x{base:g}: {diff:+.4g} ({100 * diff / b_mean:+.2f} %), "
                         f"{diff / scatter:+.2f} x its scatter")
                if q in measured_sd:
                    line += f", {diff / measured_sd[q]:+.2f} x the measurement's standard uncertainty"
                figures[f"{q}_x{factor:g}_pct"] = round(100 * diff / b_mean, 2)
            print(line, flush=True)
    print(" ".join(f"{k}={v}" for k, v in figures.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
