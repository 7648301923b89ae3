"""The health check's answer."""
from __future__ import annotations

from pydantic import Field

from service.api.responses.common import Out


class Dask(Out):
    scheduler: str
    healthy: bool
    problem: str | None
    jobs_in_flight: int


class Health(Out):
    """GET /health; the same body with status 'error' or 'degraded' answers 503."""

    status: str = Field(description="ok, degraded (the executor cannot reach its cluster) or error (storage)")
    version: str
    executor: str = Field(description="none, local or dask")
    local_workers_alive: int
    local_worker_pids: list[int]
    dask: Dask | None = None
    database: str = Field(description="'ok', 'unavailable: <error type>' or 'unreadable: <table> row <id>: <error type>' "
                                      "(the newest row of a table cannot be read back)")
    schema_revision: str | None = None
    jobs: dict[str, int] | None = Field(None, description="per job status: how many")
