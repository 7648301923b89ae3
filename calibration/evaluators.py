"""Batch evaluators: a list of (parameters, seed) in, one list of bulk-value records per run out.

The loop asks for batteries and is told their results (Optuna's pattern); it never knows whether
they ran in this process, on the engine, on a queue or on Dask. A record is a dict with test,
quantity, condition and value, SI, as ``engine.lab.result.BulkProperty`` dumps.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

from . import standin

RunRequest = tuple[Mapping[str, Any], int]
BatchEvaluator = Callable[[Sequence[RunRequest]], list[list[dict]]]


@dataclass
class StandinEvaluator:
    """The closed-form stand-in (``calibration.standin``) as a batch evaluator; counts its runs."""

    conditions: standin.Conditions = field(default_factory=standin.Conditions)
    gains: standin.Gains = field(default_factory=standin.Gains)
    noise_scale: float = 1.0
    runs: int = 0

    def __call__(self, requests: Sequence[RunRequest]) -> list[list[dict]]:
        self.runs += len(requests)
        return [standin.battery(p, seed, self.conditions, self.gains, self.noise_scale) for p, seed in requests]


@dataclass
class LabEvaluator:
    """The DEM virtual lab in this process, one battery after another (a notebook's evaluator).

    ``options`` are TestOptions fields (e.g. the DST loads and E' stresses of the targets).
    """

    fidelity: str = "screening"
    test: str = "battery"
    options: dict[str, Any] = field(default_factory=dict)
    runs: int = 0

    def __call__(self, requests: Sequence[RunRequest]) -> list[list[dict]]:
        from engine.lab import run_job
        from engine.lab.spec import JobSpec, MicroParameters, TestOptions

        out = []
        for parameters, seed in requests:
            spec = JobSpec(test=self.test, fidelity=self.fidelity, seed=int(seed),
                           parameters=MicroParameters.model_validate(dict(parameters)),
                           options=TestOptions.model_validate(self.options))
            result = run_job(spec)
            out.append([p.model_dump() for p in result.properties])
            self.runs += 1
        return out
