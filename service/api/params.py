"""Path and query parameters shared by the routers, bounded to what the database can hold.

Why: SQLite (and PostgreSQL BIGINT) integers stop at 2^63 - 1, PostgreSQL's INTEGER id columns at 2^31 - 1;
a larger id or offset used to reach the driver, overflow and answer 500 (dropping the keep-alive
connection). Bounded here, it is a 422 naming the parameter, and the bound shows in the OpenAPI schema.
"""
from __future__ import annotations

from typing import Annotated

from fastapi import Path, Query

from engine.lab.bounds import ID_MAX, SQLITE_INT_MAX

# Priorities of jobs and campaigns: one scale, higher runs first.
PRIORITY_MIN, PRIORITY_MAX = -1000, 1000


def _id(description: str):
    return Annotated[int, Path(ge=1, le=ID_MAX, description=description)]


JobId = _id("job id")
MaterialId = _id("material id")
MeasurementId = _id("measurement id")
CampaignId = _id("campaign id")
ScheduleId = _id("schedule id")
IterationNumber = Annotated[int, Path(ge=1, le=ID_MAX, description="iteration number, from 1")]
Offset = Annotated[int, Query(ge=0, le=SQLITE_INT_MAX, description="rows to skip")]


def page_limit(maximum: int):
    """A listing's ``limit``: bounded, so no request can ask for a listing of every row (``GET /materials``
    answered 7 MB per full-size material, all of them at once)."""
    return Annotated[int, Query(ge=1, le=maximum, description=f"rows per page, at most {maximum}")]


# Page sizes: default and maximum per listing, by the size of one row (a material carries its measurements).
JobLimit = page_limit(1000)
MaterialLimit = page_limit(200)
CampaignLimit = page_limit(500)
ScheduleLimit = page_limit(500)
FiringLimit = page_limit(1000)
MeasurementLimit = page_limit(1000)
IterationLimit = page_limit(100)  # an iteration carries its design, runs and report
