"""Calibration campaigns: a persisted state machine with numbered iterations.

Everything the runner needs to carry on after a restart lives in these rows
(status, phase, the runs and their job ids), never in process memory.
"""
from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import JSON, BigInteger, DateTime, ForeignKey, Integer, String, Text, UniqueConstraint
from sqlalchemy.orm import Mapped, mapped_column, relationship

from calibration.evaluator_registry import DEFAULT, NAME_MAX
from service.models.base import IDENTITY_LENGTH, Base, utcnow
from service.vocabulary import CampaignStatus

CAMPAIGN_STATUSES = CampaignStatus.values()
# Phases of one iteration, in order.
ITERATION_PHASES = ("design", "batteries", "analysis", "confirmation", "report", "done")


class Campaign(Base):
    __tablename__ = "campaigns"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), nullable=False)
    material_id: Mapped[int] = mapped_column(ForeignKey("materials.id"), index=True, nullable=False)
    status: Mapped[str] = mapped_column(String(16), default=CampaignStatus.DRAFT, index=True, nullable=False)
    evaluator: Mapped[str] = mapped_column(String(NAME_MAX), default=DEFAULT.name, nullable=False)
    fidelity: Mapped[str] = mapped_column(String(16), default="screening", nullable=False)
    # The validated CampaignConfig (factors, design, targets, options, seed ...).
    config: Mapped[dict[str, Any]] = mapped_column(JSON, nullable=False)
    current_iteration: Mapped[int] = mapped_column(Integer, default=0, nullable=False)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    schedule_id: Mapped[int | None] = mapped_column(Integer, nullable=True, index=True)
    client_id: Mapped[str] = mapped_column(String(IDENTITY_LENGTH), default="anonymous", nullable=False)
    # the user (bearer token name) who made it; None without a token (service.ownership)
    owner: Mapped[str | None] = mapped_column(String(IDENTITY_LENGTH), nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, nullable=False)
    updated_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, onupdate=utcnow, nullable=False)
    started_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True)

    iterations: Mapped[list["CampaignIteration"]] = relationship(
        back_populates="campaign", cascade="all, delete-orphan", order_by="CampaignIteration.number"
    )


class CampaignIteration(Base):
    """One pass design -> batteries -> fits -> optimum -> confirmation -> report.

    ``parameters`` keeps the fixed micro parameters and active contact effects the
    iteration used, so a later iteration that adds an effect can be compared with it.
    """

    __tablename__ = "campaign_iterations"
    __table_args__ = (UniqueConstraint("campaign_id", "number", name="uq_iteration_number"),)

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    campaign_id: Mapped[int] = mapped_column(
        ForeignKey("campaigns.id", ondelete="CASCADE"), index=True, nullable=False
    )
    number: Mapped[int] = mapped_column(Integer, nullable=False)
    phase: Mapped[str] = mapped_column(String(16), default="design", nullable=False)
    parameters: Mapped[dict[str, Any]] = mapped_column(JSON, default=dict, nullable=False)
    design: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    models: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    optimum: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    confirmation: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    report: Mapped[dict[str, Any] | None] = mapped_column(JSON, nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, nullable=False)
    finished_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True)

    campaign: Mapped[Campaign] = relationship(back_populates="iterations")
    runs: Mapped[list["CampaignRun"]] = relationship(
        back_populates="iteration", cascade="all, delete-orphan", order_by="CampaignRun.id"
    )


class CampaignRun(Base):
    """One battery of an iteration: a design point, a centre replicate or the confirmation."""

    __tablename__ = "campaign_runs"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    iteration_id: Mapped[int] = mapped_column(
        ForeignKey("campaign_iterations.id", ondelete="CASCADE"), index=True, nullable=False
    )
    kind: Mapped[str] = mapped_column(String(16), nullable=False)  # 'design' | 'confirmation' | 'diagnosis'
    std_order: Mapped[int] = mapped_column(Integer, default=0, nullable=False)
    run_order: Mapped[int] = mapped_column(Integer, default=0, nullable=False)
    is_centre: Mapped[bool] = mapped_column(default=False, nullable=False)
    coded: Mapped[dict[str, float]] = mapped_column(JSON, default=dict, nullable=False)
    natural: Mapped[dict[str, float]] = mapped_column(JSON, default=dict, nullable=False)
    seed: Mapped[int] = mapped_column(BigInteger, nullable=False)  # to MAX_SEED = 2^32 - 1, past a 32-bit INTEGER
    job_id: Mapped[int | None] = mapped_column(Integer, nullable=True, index=True)
    status: Mapped[str] = mapped_column(String(16), default="pending", nullable=False)
    responses: Mapped[dict[str, float] | None] = mapped_column(JSON, nullable=True)
    error: Mapped[str | None] = mapped_column(Text, nullable=True)
    # "iteration 1 design run 5": a battery an earlier iteration ran, reused (calibration.reuse); its
    # job_id is that battery's, and nothing is queued for it
    reused_from: Mapped[str | None] = mapped_column(String(100), nullable=True)

    iteration: Mapped[CampaignIteration] = relationship(back_populates="runs")
