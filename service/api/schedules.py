"""Schedule endpoints: cron (UTC) + campaign template, with a preview of upcoming firings."""
from __future__ import annotations

from fastapi import APIRouter, Query, Response

from service.api.openapi import errors
from service.api.params import ScheduleId
from service.api.responses.schedules import CronPreview, Firing, Schedule
from service.db import DbSession, built_then_committed
from service.errors import Invalid
from service.schedules.cron import CronError, parse_cron
from service.schedules.scheduler import naive_utc
from service.schedules.store import (ScheduleIn, ScheduleUpdate, create_schedule, delete_schedule, firing_view,
                                     get_schedule, list_schedules, schedule_view, update_schedule)

router = APIRouter(prefix="/schedules", tags=["schedules"])


@router.get("/cron-preview", summary="Check a cron expression and list its next firings (UTC)",
            response_model=CronPreview)
def cron_preview(expr: str = Query(..., max_length=200, description="e.g. '0 2 * * *'"), count: int = Query(5, ge=1, le=50)) -> dict:
    try:
        cron = parse_cron(expr)
    except CronError as exc:
        raise Invalid(str(exc), ["query", "expr"]) from exc
    return {"expr": expr, "next": [t.isoformat() + "Z" for t in cron.upcoming(naive_utc(None), count)]}


@router.post("", status_code=201, summary="Create a schedule", response_model=Schedule,
             responses=errors(404, c404="the template's material does not exist"))
def create(body: ScheduleIn, session: DbSession) -> dict:
    schedule = create_schedule(session, body, commit=False)
    return built_then_committed(session, lambda: schedule_view(schedule), Schedule)


@router.get("", summary="List schedules", response_model=list[Schedule])
def list_all(session: DbSession) -> list[dict]:
    return [schedule_view(s, firings=3) for s in list_schedules(session)]


@router.get("/{schedule_id}", response_model=Schedule)
def show(schedule_id: ScheduleId, session: DbSession) -> dict:
    return schedule_view(get_schedule(session, schedule_id))


@router.patch("/{schedule_id}", summary="Change cron, enable/disable, policy", response_model=Schedule)
def patch(schedule_id: ScheduleId, body: ScheduleUpdate, session: DbSession) -> dict:
    return schedule_view(update_schedule(session, schedule_id, body))


@router.delete("/{schedule_id}", status_code=204)
def delete(schedule_id: ScheduleId, session: DbSession):
    delete_schedule(session, schedule_id)
    return Response(status_code=204)


@router.get("/{schedule_id}/firings", summary="Every due time handled: campaign started or why skipped",
            response_model=list[Firing])
def firings(schedule_id: ScheduleId, session: DbSession) -> list[dict]:
    return [firing_view(f) for f in get_schedule(session, schedule_id).firings]
