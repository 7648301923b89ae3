"""Evaluators turn a job spec into a lab result record; workers call ``run_spec``.

'dem' runs the virtual laboratory on the numba engine; 'analytic' is a closed-form
stand-in with the same result shape, for fast tests and for demos of the
calibration loop (it can carry a hidden physical effect, see ``analytic``).
"""
from __future__ import annotations

from typing import Callable

from engine.lab.result import LabResult
from engine.lab.spec import JobSpec

EVALUATORS = ("dem", "analytic")

ProgressFn = Callable[[float, str], None]
CancelFn = Callable[[], bool]


def run_spec(
    evaluator: str,
    spec: JobSpec,
    progress: ProgressFn | None = None,
    should_cancel: CancelFn | None = None,
) -> LabResult:
    if evaluator == "analytic":
        from service.evaluators.analytic import run_analytic

        return run_analytic(spec, progress=progress, should_cancel=should_cancel)
    if evaluator == "dem":
        from engine.lab import run_job

        return run_job(spec, progress=progress, should_cancel=should_cancel)
    raise ValueError(f"unknown evaluator {evaluator!r}; choose one of {EVALUATORS}")
