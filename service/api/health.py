"""Liveness and readiness in one call: database reachable, schema revision, queue depth, executors."""
from __future__ import annotations

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse
from sqlalchemy import select, text
from sqlalchemy.orm import Session

from service import queue
from service.api.responses.common import typed
from service.api.responses.health import Health
from service.db import DbSession

router = APIRouter(tags=["health"])


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("demcal")
    except Exception:
        return "unknown"


def unreadable_table(session: Session) -> str | None:
    """The first table whose newest row cannot be read back (``"jobs row 7: JSONDecodeError"``), else None.

    Why: with row contents corrupted, ``SELECT 1`` answered and health said ok while ``/jobs`` and
    ``/campaigns`` answered 500. Each mapped table's newest row (the one listings show first) is loaded
    through the ORM, every column decoded; older rows are not read, so health stays one query per table."""
    from service.models.base import Base
    from service.models import campaign, job, material, schedule  # noqa: F401  (every table mapped)

    for mapper in sorted(Base.registry.mappers, key=lambda m: m.local_table.name):
        table = mapper.local_table.name
        key = mapper.primary_key[0]
        newest = session.scalar(select(key).order_by(key.desc()).limit(1))
        if newest is None:
            continue
        try:
            row = session.scalars(select(mapper.class_).where(key == newest)).one()
            for column in mapper.column_attrs:
                getattr(row, column.key)
        except Exception as exc:
            session.rollback()
            return f"{table} row {newest}: {type(exc).__name__}"
    return None


@router.get("/health", summary="Service health: database, schema, queue, workers", **typed(Health),
            responses={503: {"model": Health,
                             "description": "storage unavailable or the executor cannot reach its cluster"}})
def health(request: Request, session: DbSession):
    body = {"status": "ok", "version": _version(), "executor": getattr(request.app.state, "executor", "none")}
    pool = getattr(request.app.state, "worker_pool", None)
    body["local_workers_alive"] = pool.alive() if pool is not None else 0
    body["local_worker_pids"] = pool.pids() if pool is not None else []
    dispatcher = getattr(request.app.state, "dispatcher", None)
    if dispatcher is not None:
        body["dask"] = {"scheduler": str(dispatcher.scheduler), "healthy": dispatcher.healthy,
                        "problem": dispatcher.problem, "jobs_in_flight": len(dispatcher.inflight)}
    try:
        session.execute(text("SELECT 1"))
        body["database"] = "ok"
        body["schema_revision"] = session.execute(text("SELECT version_num FROM alembic_version")).scalar()
        body["jobs"] = queue.queue_counts(session)
        unreadable = unreadable_table(session)
    except Exception as exc:  # report, do not raise: health must answer even when storage is down
        body.update(status="error", database=f"unavailable: {type(exc).__name__}")
        return JSONResponse(body, status_code=503)
    if unreadable is not None:
        body.update(status="error", database=f"unreadable: {unreadable}")
        return JSONResponse(body, status_code=503)
    if dispatcher is not None and not dispatcher.healthy:  # jobs cannot run: not healthy, say why
        body["status"] = "degraded"
        return JSONResponse(body, status_code=503)
    return body
