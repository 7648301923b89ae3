"""A job's status and progress, lists of jobs, and its result record and curves."""
from __future__ import annotations

from datetime import datetime, timezone
from typing import Any

from pydantic import BaseModel, Field, field_serializer

from service.api.responses.common import CONDITION, Condition, CostEstimate, Out, Page
from service.vocabulary import JobStatus


class Progress(BaseModel):
    fraction: float
    phase: str | None


class JobOut(BaseModel):
    id: int
    status: JobStatus
    evaluator: str
    test: str
    fidelity: str
    seed: int
    priority: int
    attempts: int
    max_attempts: int
    progress: Progress
    cancel_requested: bool
    error: str | None
    engine_version: str | None
    wall_time_s: float | None
    created_at: datetime
    started_at: datetime | None
    finished_at: datetime | None
    heartbeat_at: datetime | None
    lease_owner: str | None
    lease_expires_at: datetime | None
    idempotency_key: str | None
    client_id: str
    owner: str | None = Field(None, description="the user (bearer token name) who made it; null when made without a token")
    campaign_id: int | None
    result_available: bool
    spec: dict[str, Any]
    warnings: list[str] = Field(default_factory=list,
                                description="micro parameters and test options outside their typical ranges, each "
                                            "with the unit slip it probably is (engine.lab.plausibility); the job "
                                            "runs all the same")
    estimate: CostEstimate | None = Field(None, description="at creation (POST): particles and simulated time "
                                                         "in the rig and resolution the job runs at")

    @field_serializer("created_at", "started_at", "finished_at", "heartbeat_at", "lease_expires_at")
    def _utc(self, value: datetime | None) -> str | None:
        """Stored naive UTC; sent with its zone, like the campaigns' timestamps."""
        if value is None:
            return None
        return (value if value.tzinfo else value.replace(tzinfo=timezone.utc)).isoformat().replace("+00:00", "Z")


class JobList(Page):
    items: list[JobOut]


class ResultProperty(Out):
    """One simulated bulk property, keyed like a measurement (engine.lab.result.BulkProperty); a value
    that diverged is null."""

    test: str
    quantity: str
    value: float | None = Field(description="in the unit below (SI)")
    unit: str
    condition: Condition = Field(default_factory=dict, description=CONDITION)


class ResultProvenance(Out):
    """How a result was obtained (engine.lab.result.Provenance)."""

    parameters: dict[str, Any] = Field(description="the micro-parameters run (engine.lab.spec.MicroParameters)")
    seed: int
    fidelity: str = Field(description="the preset's name, or the resolution (as_measured, coarse)")
    engine_version: str
    rig: str | None = Field(None, description="the rig the job ran in (null: stored before rigs were data)")
    scale_factor: float = Field(1.0, description="particle sizes over the material's (a coarse resolution's factor)")
    steps: int = 0
    simulated_time_s: float | None = 0.0
    wall_time_s: float | None = 0.0
    max_inertial_number: float | None = None
    warnings: list[str] = Field(default_factory=list)


Curve = dict[str, list[float | None]]


class JobResult(Out):
    """GET /jobs/{id}/result: the result record; ``curves`` absent with include_curves=false."""

    test: str
    properties: list[ResultProperty]
    curves: dict[str, Curve] | None = Field(None, description="per curve name: equal-length SI columns by name")
    provenance: ResultProvenance


class CurveIndex(Out):
    columns: list[str] = Field(description="column names, sorted")
    points: int = Field(description="length of the longest column")
