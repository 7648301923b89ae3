"""Schedules, their firings and cron previews (service.schedules.store views)."""
from __future__ import annotations

from typing import Any

from pydantic import Field

from service.api.responses.common import Out, Page


class CronPreview(Out):
    expr: str
    next: list[str] = Field(description="the next firings, ISO 8601 UTC")


class Firing(Out):
    id: int
    due_at: str | None = Field(description="ISO 8601 UTC")
    fired_at: str | None
    missed_count: int
    campaign_id: int | None = Field(description="the campaign started, if any")
    skipped_reason: str | None


class Schedule(Out):
    id: int
    name: str
    cron: str
    enabled: bool
    only_if_new_measurements: bool
    missed_run_policy: str = Field(description="coalesce or skip")
    next_run_at: str | None = Field(description="ISO 8601 UTC")
    last_run_at: str | None
    last_campaign_id: int | None
    template: dict[str, Any] = Field(description="the campaign each firing creates (CampaignCreate)")
    material_id: int | None
    owner: str | None = Field(None, description="the user (bearer token name) who made it; null when made without a token")
    recent_firings: list[Firing]


class ScheduleList(Page):
    """A page of schedules, by id."""

    items: list[Schedule]


class FiringList(Page):
    """A page of a schedule's firings, oldest first (one per due time: a daily schedule adds 365 a year)."""

    items: list[Firing]
