"""The loop's state in memory: what a notebook's loop holds where the service holds database rows.

Same attribute names as the service's ``CampaignIteration`` and ``CampaignRun`` rows, so every step of
``calibration.machine`` reads both; pydantic, so a notebook can save a loop (``model_dump_json``) and
resume it (``model_validate_json``) exactly where it stopped.
"""
from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field

from .vocabulary import Phase, RunKind


class RunState(BaseModel):
    """One battery of an iteration: where it runs (natural and coded factor values, seed) and, once
    evaluated, its responses (``calibration.keys.responses_of`` shape)."""

    id: int
    kind: RunKind
    std_order: int
    run_order: int
    is_centre: bool = False
    natural: dict[str, float]
    coded: dict[str, float] = Field(default_factory=dict)
    seed: int
    responses: dict[str, dict[str, Any]] | None = None
    job_id: int | None = None
    error: str | None = None
    reused_from: str | None = None  # a battery of an earlier iteration (calibration.reuse): not run again

    @property
    def status(self) -> str:
        return "succeeded" if self.responses is not None else "pending"


class IterationState(BaseModel):
    """One iteration: its phase, the settings it runs with (``parameters``) and what each phase stored."""

    number: int
    phase: Phase = Phase.DESIGN
    parameters: dict[str, Any] = Field(default_factory=dict)
    design: dict[str, Any] | None = None
    models: dict[str, Any] | None = None
    optimum: dict[str, Any] | None = None
    confirmation: dict[str, Any] | None = None
    report: dict[str, Any] | None = None
    runs: list[RunState] = Field(default_factory=list)


class LoopState(BaseModel):
    """The whole loop: the settings the next iteration runs with, the iterations so far, and whether
    the loop is over."""

    settings: dict[str, Any]
    iterations: list[IterationState] = Field(default_factory=list)
    complete: bool = False
    next_run_id: int = 1
