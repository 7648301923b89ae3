"""Liveness and readiness in one call: database reachable, schema revision, queue depth, executors."""
from __future__ import annotations

from fastapi import APIRouter, Request
from fastapi.responses import JSONResponse
from sqlalchemy import text

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
    except Exception as exc:  # report, do not raise: health must answer even when storage is down
        body.update(status="error", database=f"unavailable: {type(exc).__name__}")
        return JSONResponse(body, status_code=503)
    if dispatcher is not None and not dispatcher.healthy:  # jobs cannot run: not healthy, say why
        body["status"] = "degraded"
        return JSONResponse(body, status_code=503)
    return body
