"""E_ur and E' per stress on screening packings, Hertz-Mindlin against linear springs (docs/lab.md, unload-reload).

At the tier-B truth (bench/diagnosis_dem.py's TRUTH), Hertz-Mindlin at the modulus matched to kp at 30 kPa
(engine.effects.hertz_mindlin.matched_young_modulus_pa): one fill and CCT per law and seed, E' and E_ur at the
given stresses, and the ratio of the highest stress's value to the lowest's. Prints a line per run.

    python3 bench/unload_reload.py --seeds 1 2 3      # about 30 s per run on one core
"""
from __future__ import annotations

import argparse
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.dirname(os.path.abspath(__file__))))

from engine.effects.hertz_mindlin import matched_young_modulus_pa  # noqa: E402
from engine.lab.battery import run_job  # noqa: E402
from engine.lab.spec import JobSpec, MicroParameters  # noqa: E402

TRUTH = {"particle_density_kg_m3": 2650.0, "friction_pp": 0.6, "friction_pw": 0.5, "particle_stiffness_n_per_m": 2.0e6}


def run(law: str, seed: int, stresses_pa: list[float]) -> dict[str, list[float]]:
    parameters = dict(TRUTH)
    if law == "hertz":
        parameters["effects"] = {"hertz_mindlin": {"young_modulus_pa": matched_young_modulus_pa(MicroParameters(**TRUTH))}}
    result = run_job(JobSpec(test="cct", fidelity="screening", seed=seed, parameters=parameters,
                             options={"cct_window_stresses_pa": stresses_pa, "cct_unload_reload_stresses_pa": stresses_pa}))
    by = {"unload_reload_modulus_pa": {}, "confined_modulus_pa": {}}
    for p in result.properties:
        if p.quantity in by and p.condition:
            by[p.quantity][p.condition["normal_stress_pa"]] = p.value
    return {q: [values.get(s, float("nan")) for s in stresses_pa] for q, values in by.items()}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[1, 2, 3])
    ap.add_argument("--stresses-kpa", type=float, nargs="+", default=[3.0, 10.0, 30.0, 60.0])
    args = ap.parse_args()
    stresses = [s * 1e3 for s in args.stresses_kpa]
    print("stresses, kPa:", ", ".join(f"{s:g}" for s in args.stresses_kpa))
    for seed in args.seeds:
        for law in ("hertz", "linear"):
            t0 = time.time()
            out = run(law, seed, stresses)
            ur, e = out["unload_reload_modulus_pa"], out["confined_modulus_pa"]
            print(f"{law:6s} seed {seed}: E_ur " + ", ".join(f"{v / 1e6:.2f}" for v in ur)
                  + f" MPa (last/first {ur[-1] / ur[0]:.2f}); E' " + ", ".join(f"{v / 1e6:.2f}" for v in e)
                  + f" MPa (last/first {e[-1] / e[0]:.2f}); {time.time() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
