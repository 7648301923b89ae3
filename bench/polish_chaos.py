"""Does the polish lower the true misfit when the simulator is chaotic?

On the DEM engine two batteries at one seed but nearby parameters share little of their packing's randomness
(session 39, hertz_strong: responses at one seed correlated 0.0-0.1 between the optimum and points 0.1 coded
away), so the polish (``calibration.polish``) compares its points on unpaired noisy misfits: a point's chi2 over 8
seeds moved by 8-20 between bootstrap draws of its seeds, as much as the steps gained. Whether its greedy rule
("take the trial if its chi2 is lower") then follows the noise is measured here, on tier A's worlds with the
stand-in made chaotic (``StandinEvaluator(chaotic=True)``: each run's scatter drawn from its seed and parameters)
and its scatter scaled as on the engine. For every iteration that polished, the stand-in without scatter gives
the true misfit (chi2 with the priors, as the polish judges it) at the surfaces' optimum and at the polished
point. Printed: how often the polish raised the true misfit, and the median ratio final / start.

Since session 41 a polish that took a step runs the chosen point again at fresh seeds (``polish_holdout``), and
the report reads those. Also printed, over the iterations with a step: the mean excess of a misfit on batteries
over the true misfit at the chosen point, on the seeds the steps chose on and on the held-out ones. Both are drawn
alike (m batteries, the simulator's sd estimated from them, so the excess may be negative: the true misfit divides
by the measurement's variance alone), so their means would agree if the choice took nothing from the noise; the
chosen seeds' excess falling short of the held-out's is the choice's flattery (a winner's curse). And, for the
iterations whose model is the true world's, how far the polished point's true misfit stays above the truth's own
(tier B's criterion "within 1.1 x the truth", here free of scatter).

    python3 bench/polish_chaos.py --cases 40 --noise-scale 5
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from calibration import analysis, polish, standin  # noqa: E402
from calibration import parameters as factor_paths  # noqa: E402
from calibration.conditions import standin_conditions  # noqa: E402
from calibration.evaluators import StandinEvaluator  # noqa: E402
from calibration.loop import CalibrationLoop  # noqa: E402
from calibration.replay import iteration_fixed  # noqa: E402
from calibration.testbed import OPTIONS, loop_settings, make_case  # noqa: E402
from calibration.vocabulary import RunKind  # noqa: E402


def true_chi2(evaluator: StandinEvaluator, settings, targets, it, natural: dict, seeds: list[int]) -> float:
    """The polish's misfit at ``natural`` with the stand-in's batteries free of scatter (the same at every seed)."""
    params = factor_paths.apply(iteration_fixed(it.parameters), natural)
    records = [standin.battery(params, seed, evaluator.conditions, evaluator.gains, 0.0) for seed in seeds]
    design, models = analysis.fit(it.design["doe"], [r for r in it.runs if r.kind == RunKind.DESIGN], targets)
    modelled = [m for m in models if m.fit is not None]
    return polish._residuals(settings, design, modelled, natural, records, seeds).chi2()


def polished(case_seed: int, kind: str, noise_scale: float, chaotic: bool,
             polish_steps: int | None = None) -> list[dict]:
    """One tier A case run through the loop: a row per iteration whose polish took its batteries
    (``polish_steps``: the loop's setting, None for its default)."""
    case = make_case(case_seed, kind)
    settings = loop_settings(case, 3)
    if polish_steps is not None:
        settings = settings.model_copy(update={"polish_steps": polish_steps})
    evaluator = StandinEvaluator(standin_conditions(OPTIONS), noise_scale=noise_scale, chaotic=chaotic)
    loop = CalibrationLoop(case.targets, evaluator, settings)
    result = loop.run()
    rows = []
    for it in result.iterations:
        state = (it.optimum or {}).get("polish") or {}
        if not state or "skipped" in state or not state.get("batteries"):
            continue
        seeds = polish.seeds_of(state)
        start = it.optimum.get("surrogate_parameters") or state["theta"]
        # the truth's own point, where the iteration's model is the true world's (its effects, every factor known)
        at_truth = {name: factor_paths.read(case.truth, name) for name in state["theta"]}
        same_model = analysis.active_effects(it.parameters) == set(case.truth.get("effects") or {})
        rows.append({"case": case_seed, "iteration": it.number, "steps": state["steps"],
                     "batteries": state["batteries"], "noisy": (state["chi2_start"], state["chi2"]),
                     "holdout": state.get("holdout_chi2"),
                     "true": (true_chi2(evaluator, settings, loop.targets, it, start, seeds),
                              true_chi2(evaluator, settings, loop.targets, it, state["theta"], seeds)),
                     "truth": (true_chi2(evaluator, settings, loop.targets, it, at_truth, seeds)
                               if same_model and None not in at_truth.values() else None)})
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--cases", type=int, default=40, help="tier A cases 0..N-1 (default 40)")
    ap.add_argument("--kind", default="single", help="tier A's kind of case (default single)")
    ap.add_argument("--noise-scale", type=float, default=5.0, help="the stand-in's scatter x this (default 5)")
    ap.add_argument("--paired", action="store_true", help="the stand-in's own seeds, which pair every run")
    ap.add_argument("--polish-steps", type=int, default=None,
                    help="Gauss-Newton steps the polish may take (default: the loop's, 3; at most 6)")
    args = ap.parse_args(argv)
    if args.cases < 1 or args.noise_scale < 0:
        ap.error("--cases must be at least 1 and --noise-scale not negative")
    if args.polish_steps is not None and not 0 <= args.polish_steps <= 6:
        ap.error("--polish-steps must be 0-6 (the loop's own bounds)")
    t0 = time.time()
    rows = []
    for seed in range(args.cases):
        for row in polished(seed, args.kind, args.noise_scale, not args.paired, args.polish_steps):
            rows.append(row)
            (a, b), (n0, n1) = row["true"], row["noisy"]
            print(f"case {row['case']:3d} iteration {row['iteration']}: {row['steps']} step(s), {row['batteries']} "
                  f"batteries; chi2 on the batteries {n0:.1f} -> {n1:.1f}, true {a:.1f} -> {b:.1f}"
                  + (f", held out {row['holdout']:.1f}" if row["holdout"] is not None else "")
                  + (f", at the truth {row['truth']:.1f}" if row["truth"] is not None else ""), flush=True)
    stepped = [r for r in rows if r["steps"]]
    raised = sum(r["true"][1] > r["true"][0] * (1 + 1e-9) for r in stepped)
    ratio = statistics.median(r["true"][1] / r["true"][0] for r in stepped) if stepped else float("nan")
    held = [r for r in stepped if r["holdout"] is not None]
    if held:
        chosen = [r["noisy"][1] - r["true"][1] for r in held]
        fresh = [r["holdout"] - r["true"][1] for r in held]
        diff = [f - c for f, c in zip(fresh, chosen)]
        print(f"excess over the true misfit at the chosen point, {len(held)} iterations: on the seeds chosen on "
              f"{statistics.mean(chosen):.2f}, held out {statistics.mean(fresh):.2f}, held out - chosen "
              f"{statistics.mean(diff):.2f} +- {statistics.stdev(diff) / len(diff) ** 0.5 if len(diff) > 1 else float('nan'):.2f}")
    true_model = [r for r in stepped if r["truth"] is not None and r["truth"] > 0]
    if true_model:
        gap = sorted(r["true"][1] / r["truth"] for r in true_model)
        print(f"the true model's iterations with a step, {len(true_model)}: true misfit at the polished point over "
              f"the truth's own, median {statistics.median(gap):.2f}, within 1.1 x in {sum(g <= 1.1 for g in gap)}, "
              f"above 2 x in {sum(g > 2.0 for g in gap)}")
    steps = "default" if args.polish_steps is None else args.polish_steps
    print(f"polished_iterations={len(rows)} stepped={len(stepped)} true_chi2_raised={raised} "
          f"median_true_ratio={ratio:.3f} batteries={sum(r['batteries'] for r in rows)} "
          f"chaotic={not args.paired} noise_scale={args.noise_scale:g} polish_steps={steps} "
          f"wall_s={time.time() - t0:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
