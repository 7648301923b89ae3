"""Run a design through any batch evaluator: parameters in, responses out.

The evaluator contract (docs/architecture.md) is
`Callable[[list[dict[str, float]]], list[dict[str, float]]]`, so the same code
drives the DEM engine through the job queue or `AnalyticEvaluator` in tests.
"""
from __future__ import annotations

import math
from typing import Callable

import numpy as np

from .designs import Design
from .factors import DoeError

Evaluator = Callable[[list[dict[str, float]]], list[dict[str, float]]]


def run_design(design: Design, evaluator: Evaluator, *, batch_size: int | None = None,
               include_seed: bool = False) -> list[dict[str, float]]:
    """Evaluate every run in run order; return responses aligned with the design rows (std order).

    include_seed adds each run's simulator seed to its parameter dict under 'seed',
    for evaluators whose noise depends on it.
    """
    params = design.parameter_sets("run")
    if include_seed:
        seeds = design.seed[design.run_to_std()]
        params = [{**p, "seed": float(s)} for p, s in zip(params, seeds)]
    step = batch_size or len(params)
    if step < 1:
        raise DoeError("batch_size must be positive")
    out_run: list[dict[str, float]] = []
    for i in range(0, len(params), step):
        chunk = params[i:i + step]
        res = list(evaluator(chunk))
        if len(res) != len(chunk):
            raise DoeError(f"evaluator returned {len(res)} results for {len(chunk)} parameter sets")
        out_run.extend({k: float(v) for k, v in r.items()} for r in res)
    by_std: list[dict[str, float]] = [{} for _ in params]
    for pos, row in enumerate(design.run_to_std()):
        by_std[row] = out_run[pos]
    return by_std


class AnalyticEvaluator:
    """Stand-in simulator: closed-form responses plus seeded Gaussian noise.

    With a 'seed' in the parameter dict the noise is drawn from that seed, so a run
    repeated with the same seed returns the same value, as a deterministic DEM run does.
    """

    def __init__(self, functions: dict[str, Callable[[dict[str, float]], float]],
                 noise_sd: dict[str, float] | None = None, seed: int = 0):
        self.functions = dict(functions)
        self.noise_sd = dict(noise_sd or {})
        self._rng = np.random.default_rng(seed)
        self.calls = 0

    def __call__(self, parameter_sets: list[dict[str, float]]) -> list[dict[str, float]]:
        out = []
        for p in parameter_sets:
            p = dict(p)
            run_seed = p.pop("seed", None)
            rng = np.random.default_rng(int(run_seed)) if run_seed is not None else self._rng
            row = {}
            for name, fn in self.functions.items():
                v = float(fn(p))
                sd = self.noise_sd.get(name, 0.0)
                row[name] = v + (float(rng.normal(0.0, sd)) if sd > 0 else 0.0)
                if not math.isfinite(row[name]):
                    raise DoeError(f"analytic response {name} is not finite at {p}")
            out.append(row)
            self.calls += 1
        return out
