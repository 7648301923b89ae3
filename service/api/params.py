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
