"""Cron schedules that start campaigns from a template, and their firing log."""
from __future__ import annotations

from datetime import datetime
from typing import Any

from sqlalchemy import JSON, Boolean, DateTime, ForeignKey, Integer, String, Text
from sqlalchemy.orm import Mapped, mapped_column, relationship

from service.models.base import IDENTITY_LENGTH, Base, utcnow


class Schedule(Base):
    __tablename__ = "schedules"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    name: Mapped[str] = mapped_column(String(200), nullable=False)
    cron: Mapped[str] = mapped_column(String(100), nullable=False)  # 5 fields, UTC
    # A campaign create body (CampaignCreate); material_id inside it.
    template: Mapped[dict[str, Any]] = mapped_column(JSON, nullable=False)
    only_if_new_measurements: Mapped[bool] = mapped_column(Boolean, default=False, nullable=False)
    enabled: Mapped[bool] = mapped_column(Boolean, default=True, nullable=False)
    missed_run_policy: Mapped[str] = mapped_column(String(16), default="coalesce", nullable=False)
    next_run_at: Mapped[datetime] = mapped_column(DateTime, nullable=False)
    last_run_at: Mapped[datetime | None] = mapped_column(DateTime, nullable=True)
    # Highest measurement id of the material seen at the last start (new data marker).
    last_measurement_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    last_campaign_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    # the user (bearer token name) who made it; None without a token (service.ownership)
    owner: Mapped[str | None] = mapped_column(String(IDENTITY_LENGTH), nullable=True)
    # the identity per-client limits count against, as the creator's requests had it: the campaigns it
    # starts queue under it, so a schedule is no way past its owner's limit (None: rows from before
    # 0003, whose campaigns count as "schedule:<id>")
    client_id: Mapped[str | None] = mapped_column(String(IDENTITY_LENGTH), nullable=True)
    created_at: Mapped[datetime] = mapped_column(DateTime, default=utcnow, nullable=False)

    firings: Mapped[list["ScheduleFiring"]] = relationship(
        back_populates="schedule", cascade="all, delete-orphan", order_by="ScheduleFiring.id"
    )


class ScheduleFiring(Base):
    """What happened at each due time: a campaign started, or why it was skipped."""

    __tablename__ = "schedule_firings"

    id: Mapped[int] = mapped_column(Integer, primary_key=True)
    schedule_id: Mapped[int] = mapped_column(
        ForeignKey("schedules.id", ondelete="CASCADE"), index=True, nullable=False
    )
    due_at: Mapped[datetime] = mapped_column(DateTime, nullable=False)
    fired_at: Mapped[datetime] = mapped_column(DateTime, nullable=False)
    missed_count: Mapped[int] = mapped_column(Integer, default=0, nullable=False)
    campaign_id: Mapped[int | None] = mapped_column(Integer, nullable=True)
    skipped_reason: Mapped[str | None] = mapped_column(Text, nullable=True)

    schedule: Mapped[Schedule] = relationship(back_populates="firings")
