"""A queued DEM (or analytic) run: the row *is* the queue entry and the result record.

Everything needed to replay the run is kept: full spec (with seed), evaluator,
engine version and timings. Lease columns implement at-least-once execution with
late acknowledgement (see ``service.queue``).
"""
from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import JSON, BigInteger, Boolean, DateTime, Float, Index, Integer, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column

from calibration.evaluator_registry import DEFAULT, NAME_MAX
from service.models.base import IDENTITY_LENGTH, Base, utcnow
from service.vocabulary import JobStatus

JOB_STATUSES = JobStatus.values()
FINISHED_STATUSES = tuple(s.value for s in JobStatus.finished())


class Job(Base):
    __tablename__ = "jobs"
    __table_args__ = (
        UniqueConstraint("client_id", "idempotency_key", name="uq_jobs_client_idempotency"),
        # The claim query: queued jobs by priority, oldest first.
        Index("ix_jobs_claim", "status", "priority", "id"),
    )

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    status: Mapped[str] = mapped_column(String(16), default=JobStatus.QUEUED, nullable=False, index=True)
    evaluator: Mapped[str] = mapped_column(String(NAME_MAX), default=DEFAULT.name, nullable=False)
    test: Mapped[str] = mapped_column(String(16), nullable=False, index=True)
    fidelity: Mapped[str] = mapped_column(String(16), nullable=False)
    spec: Mapped[dict[str, Any]] = mapped_column(JSON, nullable=False)
    seed: Mapped[int] = mapped_column(BigInteger, nullable=False)  # to MAX_SEED = 2^32 - 1, past a 32-bit INTEGER
    priority: Mapped[int] = mapped_column(Integer, default=0, nullable=False)
    attempts: Mapped[int] = mapped_column(Integer, default=0, nullable=False)
    max_attempts: Mapped[int] = mapped_column(Integer, default=3, nullable=False)
    lease_owner: Mapped[str | None] = mapped_column(String(100), nullable=True)
    lease_expires_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True, index=True)
    heartbeat_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True)
    cancel_requested: Mapped[bool] = mapped_column(Boolean, default=False, nullable=False)
    progress_fraction: Mapped[float] = mapped_column(Float, default=0.0, nullable=False)
    progress_phase: Mapped[str | None] = mapped_column(String(64), nullable=True)
    result: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    engine_version: Mapped[str | None] = mapped_column(String(64), nullable=True)
    wall_time_s: Mapped[float | None] = mapped_column(Float, nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, nullable=False)
    started_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True)
    idempotency_key: Mapped[str | None] = mapped_column(String(200), nullable=True)
    client_id: Mapped[str] = mapped_column(String(IDENTITY_LENGTH), default="anonymous", nullable=False)
    campaign_id: Mapped[int | None] = mapped_column(Integer, nullable=True, index=True)
    # the user (bearer token name) who made it; None without a token (service.ownership)
    owner: Mapped[str | None] = mapped_column(String(IDENTITY_LENGTH), nullable=True)
