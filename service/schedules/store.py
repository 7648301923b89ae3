"""Schedules service layer: validation of cron and template, create/update/delete, views."""
from __future__ import annotations

from datetime import datetime
from typing import Any, Literal

from pydantic import BaseModel, Field
from sqlalchemy import select
from sqlalchemy.orm import Session

from engine.lab.spec import STRICT_INPUT
from service.campaigns.schemas import CampaignCreate
from service.errors import Invalid, NotFound
from service.campaigns.store import check_limits_with_targets
from service.materials.store import get_material
from service.models.schedule import Schedule, ScheduleFiring
from service.pagination import paged
from service.schedules.cron import CronError, parse_cron
from service.schedules.scheduler import naive_utc


class ScheduleIn(BaseModel):
    model_config = STRICT_INPUT

    name: str = Field(..., min_length=1, max_length=200)
    cron: str = Field(..., max_length=200, description="5 fields, UTC: minute hour day-of-month month day-of-week; or @daily ...")
    template: CampaignCreate = Field(..., description="the campaign each firing creates and starts")
    only_if_new_measurements: bool = Field(False, description="fire only when the material has new measurements")
    enabled: bool = True
    missed_run_policy: Literal["coalesce", "skip"] = "coalesce"


class ScheduleUpdate(BaseModel):
    model_config = STRICT_INPUT

    cron: str | None = Field(None, max_length=200)
    enabled: bool | None = None
    only_if_new_measurements: bool | None = None
    missed_run_policy: Literal["coalesce", "skip"] | None = None


def _cron(expression: str):
    try:
        return parse_cron(expression)
    except CronError as exc:
        raise Invalid(str(exc), "cron") from exc


def create_schedule(session: Session, body: ScheduleIn, now: datetime | None = None, commit: bool = True, *,
                    owner: str | None = None, client_id: str | None = None) -> Schedule:
    """A schedule; ``commit=False`` leaves the commit to the caller (``service.db.built_then_committed``).
    ``owner`` and ``client_id`` are its creator's: the campaigns it starts are theirs, and their jobs count
    against the creator's per-client limit."""
    cron = _cron(body.cron)
    if get_material(session, body.template.material_id) is None:
        raise NotFound(f"material {body.template.material_id} not found", "template.material_id")
    # every campaign a firing creates must be able to queue its runs: the same limits as a campaign
    check_limits_with_targets(session, body.template, "template.")
    schedule = Schedule(name=body.name, cron=body.cron, template=body.template.model_dump(mode="json"),
                        only_if_new_measurements=body.only_if_new_measurements, enabled=body.enabled,
                        missed_run_policy=body.missed_run_policy, next_run_at=cron.next_after(naive_utc(now)),
                        owner=owner, client_id=client_id)
    session.add(schedule)
    if commit:
        session.commit()
    return schedule


def get_schedule(session: Session, schedule_id: int) -> Schedule:
    schedule = session.get(Schedule, schedule_id, populate_existing=True)
    if schedule is None:
        raise NotFound(f"schedule {schedule_id} not found", ["path", "schedule_id"])
    return schedule


def list_schedules(session: Session, limit: int = 100, offset: int = 0) -> tuple[list[Schedule], int]:
    """A page of schedules by id, and the total."""
    return paged(session, Schedule, order=(Schedule.id,), limit=limit, offset=offset)


def list_firings(session: Session, schedule_id: int, limit: int = 100,
                 offset: int = 0) -> tuple[list[ScheduleFiring], int]:
    """A page of a schedule's firings, oldest first, and the total (404 for a schedule that does not exist)."""
    get_schedule(session, schedule_id)
    return paged(session, ScheduleFiring, where=[ScheduleFiring.schedule_id == schedule_id],
                 order=(ScheduleFiring.id,), limit=limit, offset=offset)


def update_schedule(session: Session, schedule_id: int, body: ScheduleUpdate, now: datetime | None = None) -> Schedule:
    schedule = get_schedule(session, schedule_id)
    if body.cron is not None:
        schedule.next_run_at = _cron(body.cron).next_after(naive_utc(now))
        schedule.cron = body.cron
    if body.enabled is not None:
        if body.enabled and not schedule.enabled:  # re-enabled: no catch-up for the disabled period
            schedule.next_run_at = _cron(schedule.cron).next_after(naive_utc(now))
        schedule.enabled = body.enabled
    if body.only_if_new_measurements is not None:
        schedule.only_if_new_measurements = body.only_if_new_measurements
    if body.missed_run_policy is not None:
        schedule.missed_run_policy = body.missed_run_policy
    session.commit()
    return schedule


def delete_schedule(session: Session, schedule_id: int) -> None:
    session.delete(get_schedule(session, schedule_id))
    session.commit()


def firing_view(f: ScheduleFiring) -> dict[str, Any]:
    return {"id": f.id, "due_at": _iso(f.due_at), "fired_at": _iso(f.fired_at), "missed_count": f.missed_count,
            "campaign_id": f.campaign_id, "skipped_reason": f.skipped_reason}


def schedule_view(s: Schedule, firings: int = 10) -> dict[str, Any]:
    return {"id": s.id, "name": s.name, "cron": s.cron, "enabled": s.enabled,
            "only_if_new_measurements": s.only_if_new_measurements, "missed_run_policy": s.missed_run_policy,
            "next_run_at": _iso(s.next_run_at), "last_run_at": _iso(s.last_run_at),
            "last_campaign_id": s.last_campaign_id, "template": s.template,
            "material_id": (s.template or {}).get("material_id"), "owner": s.owner,
            "recent_firings": [firing_view(f) for f in s.firings[-firings:]] if firings else []}


def _iso(value) -> str | None:
    return value.isoformat() + "Z" if value is not None else None
