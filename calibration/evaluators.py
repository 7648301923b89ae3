"""Batch evaluators: a list of (parameters, seed) in, one list of bulk-value records per run out.

The loop asks for batteries and is told their results (Optuna's pattern); it never knows whether
they ran in this process, on the engine, on a queue or on Dask. A record is a dict with test,
quantity, condition and value, SI, as ``engine.lab.result.BulkProperty`` dumps. The backends a
batch can run on (the DEM lab, the analytic stand-in) are declared in ``evaluator_registry``;
``LabEvaluator`` runs any of them here, ``StandinEvaluator`` is the bare stand-in with adjustable
gains and noise for the library's own tests.
"""
from __future__ import annotations

import json
import zlib
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence

from . import standin
from .evaluator_registry import DEM, Backend

RunRequest = tuple[Mapping[str, Any], int]
BatchEvaluator = Callable[[Sequence[RunRequest]], list[list[dict]]]


@dataclass
class StandinEvaluator:
    """The closed-form stand-in (``calibration.standin``) as a batch evaluator; counts its runs."""

    conditions: standin.Conditions = field(default_factory=standin.Conditions)
    gains: standin.Gains = field(default_factory=standin.Gains)
    noise_scale: float = 1.0
    runs: int = 0
    # each run's scatter drawn from its seed and its parameters together: no two parameter sets share it even at
    # one seed, as on the DEM engine, where a packing's randomness diverges with any change (chaos; session 39
    # measured responses at one seed correlated 0.0-0.1 between points 0.1 coded apart). Without it a seed's
    # scatter is the same at every parameter set and common seeds pair the runs perfectly.
    chaotic: bool = False

    def __call__(self, requests: Sequence[RunRequest]) -> list[list[dict]]:
        self.runs += len(requests)
        return [standin.battery(p, self._seed(p, seed), self.conditions, self.gains, self.noise_scale)
                for p, seed in requests]

    def _seed(self, parameters: Mapping[str, Any], seed: int) -> int:
        if not self.chaotic:
            return seed
        return zlib.crc32(json.dumps([parameters, int(seed)], sort_keys=True, default=str).encode())


@dataclass
class LabEvaluator:
    """A registered backend in this process, one battery after another (a notebook's evaluator):
    by default the DEM virtual lab; ``evaluator_registry.get(name).batch(...)`` builds one for any.

    ``options`` are TestOptions fields (e.g. the DST loads and E' stresses of the targets). The job
    spec is the one a queued job of the same parameters and seed carries, so a notebook and the
    service run the same thing.
    """

    fidelity: str = "screening"
    test: str = "battery"
    options: dict[str, Any] = field(default_factory=dict)
    backend: Backend = DEM
    runs: int = 0
    lab: dict[str, Any] = field(default_factory=dict)  # LoopSettings.lab: a resolution, its rig and particles

    def __call__(self, requests: Sequence[RunRequest]) -> list[list[dict]]:
        from .conditions import job_spec

        out = []
        for parameters, seed in requests:
            spec = job_spec(self.test, self.fidelity, seed, parameters, self.options, self.lab)
            result = self.backend.run(spec)
            out.append([p.model_dump() for p in result.properties])
            self.runs += 1
        return out
