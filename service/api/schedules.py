"""Schedule endpoints: cron (UTC) + campaign template, with a preview of upcoming firings."""
from __future__ import annotations

from fastapi import APIRouter, Depends, Query, Response

from service.api.openapi import errors
from service.api.params import FiringLimit, Offset, ScheduleId, ScheduleLimit
from service.api.responses.schedules import CronPreview, FiringList, Schedule, ScheduleList
from service.db import DbSession, built_then_committed
from service.errors import Invalid
from service.ownership import Caller, caller, owner_of
from service.schedules.cron import CronError, parse_cron
from service.schedules.scheduler import naive_utc
from service.schedules.store import (ScheduleIn, ScheduleUpdate, create_schedule, delete_schedule, firing_view,
                                     get_schedule, list_firings, list_schedules, schedule_view, update_schedule)
from service.security import client_id

router = APIRouter(prefix="/schedules", tags=["schedules"])
_OWNED = errors(403, c403="another user's schedule")


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
def create(body: ScheduleIn, session: DbSession, owner: str | None = Depends(owner_of),
           client: str = Depends(client_id)) -> dict:
    schedule = create_schedule(session, body, commit=False, owner=owner, client_id=client)
    return built_then_committed(session, lambda: schedule_view(schedule), Schedule)


@router.get("", summary="List schedules, by id; a page and the total", response_model=ScheduleList)
def list_all(session: DbSession, limit: ScheduleLimit = 100, offset: Offset = 0) -> dict:
    rows, total = list_schedules(session, limit, offset)
    return {"items": [schedule_view(s, firings=3) for s in rows], "total": total, "limit": limit, "offset": offset}


@router.get("/{schedule_id}", response_model=Schedule)
def show(schedule_id: ScheduleId, session: DbSession) -> dict:
    return schedule_view(get_schedule(session, schedule_id))


def _owned(session, schedule_id: int, who: Caller) -> None:
    who.require(get_schedule(session, schedule_id).owner, f"schedule {schedule_id}", ["path", "schedule_id"])


@router.patch("/{schedule_id}", summary="Change cron, enable/disable, policy", response_model=Schedule,
              responses=_OWNED)
def patch(schedule_id: ScheduleId, body: ScheduleUpdate, session: DbSession, who: Caller = Depends(caller)) -> dict:
    _owned(session, schedule_id, who)
    return schedule_view(update_schedule(session, schedule_id, body))


@router.delete("/{schedule_id}", status_code=204, responses=_OWNED)
def delete(schedule_id: ScheduleId, session: DbSession, who: Caller = Depends(caller)):
    _owned(session, schedule_id, who)
    delete_schedule(session, schedule_id)
    return Response(status_code=204)


@router.get("/{schedule_id}/firings", summary="Every due time handled, oldest first: campaign started or why "
            "skipped; a page and the total", response_model=FiringList)
def firings(schedule_id: ScheduleId, session: DbSession, limit: FiringLimit = 100, offset: Offset = 0) -> dict:
    rows, total = list_firings(session, schedule_id, limit, offset)
    return {"items": [firing_view(f) for f in rows], "total": total, "limit": limit, "offset": offset}
