"""Time to fit four responses and calibrate four parameters (target: under 1 s).

A 2^4 design with four centre runs is run through the analytic stand-in
evaluator; the timed part is what a campaign iteration does after its runs
finish: fit every response (OLS + ANOVA + effects), then a multi-start
constrained calibration with reachability. Usage: python bench/doe.py [repeats]
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

# This file is named doe.py: drop its own folder from the path so `import doe` finds the package.
_HERE = Path(__file__).resolve().parent
sys.path[:] = [p for p in sys.path if Path(p or ".").resolve() != _HERE]
sys.path.insert(0, str(_HERE.parent))

from doe import AnalyticEvaluator, calibrate, fit_responses, make_design, run_design  # noqa: E402
from doe.synthetic import FACTORS, NOISE, RESPONSES  # noqa: E402

TRUE = {"particle_density_kg_m3": 2650.0, "friction_pp": 0.45, "friction_pw": 0.3, "stiffness_n_m": 3e6}


def main(repeats: int = 5) -> None:
    design = make_design(FACTORS, full=True, center_runs=4, seed=42)
    results = run_design(design, AnalyticEvaluator(RESPONSES, NOISE), include_seed=True)
    targets = [{"response": r, "value": fn(TRUE), "uncertainty": NOISE[r]} for r, fn in RESPONSES.items()]
    fit_t, opt_t = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fits = fit_responses(design, results)
        t1 = time.perf_counter()
        cal = calibrate(fits, targets, constraints=["friction_pw <= friction_pp"], n_starts=8, seed=0)
        t2 = time.perf_counter()
        fit_t.append(t1 - t0)
        opt_t.append(t2 - t1)
    best_fit, best_opt = min(fit_t), min(opt_t)
    print(f"design: {design.kind}, {design.n_runs} runs; 4 responses, 4 parameters, 8 starts")
    print(f"fit 4 responses:        {best_fit * 1e3:8.1f} ms (best of {repeats})")
    print(f"calibrate 4 parameters: {best_opt * 1e3:8.1f} ms (best of {repeats}; incl. reachability)")
    print(f"total:                  {(best_fit + best_opt) * 1e3:8.1f} ms   target < 1000 ms")
    print("recovered: " + ", ".join(f"{k}={v:.4g} (true {TRUE[k]:.4g})" for k, v in cal.parameters.items()))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 5)
