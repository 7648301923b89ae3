"""How long a job will take on this service, before it runs: the cost model scaled by this host's own record.

Why from the service's record and not from a formula: the cost model (``engine.lab.cost``) knows a job's
particles and the simulated time it allows, but the wall time also depends on the host, on how many batteries
share its cores, and on the time step (stiffness and the smallest grain), none of which a formula knows.
Every finished job stores its wall time, so the service measures its own ratio

    r = wall seconds / (estimated particles x estimated simulated seconds)

over its latest finished jobs of the same evaluator, and a new job's wall time is median(r) x its own
particles x simulated seconds. Because r divides the actual time by the same ceilings the new job's estimate
uses, the ceilings' bias cancels. Jobs of the same set-up (test, rig, resolution and size factor) are used
when there are any, since their time step is alike (the contact law too: a Hertzian battery takes about 3x the
steps of a linear one); otherwise the evaluator's other jobs, and the basis says so. With no finished job there is no estimate, said as such rather than guessed.
"""
from __future__ import annotations

import json
import statistics
from functools import lru_cache
from typing import Any

from sqlalchemy import select
from sqlalchemy.orm import Session

from service.models.job import Job
from service.vocabulary import JobStatus

# the latest finished jobs the ratio is taken over: enough for a stable median, recent enough to follow the host
RECENT_JOBS = 30


@lru_cache(maxsize=1024)
def _footprint(spec_json: str) -> tuple[tuple[str, str, str, float, str], float] | None:
    """A stored spec's set-up and its cost model's particles x simulated seconds (specs never change, so the
    digest is cached by their text); None where this version cannot read the spec any more."""
    from engine.lab.cost import estimate_view
    from engine.lab.spec import JobSpec

    try:
        spec = JobSpec.model_validate(json.loads(spec_json))
        view = estimate_view(spec)
    except ValueError:  # pydantic's ValidationError and the lab's SpecFieldError are ValueErrors
        return None
    size = view["particles"] * view["simulated_time_s"]
    return (setup_of(spec.test, view), size) if size > 0 else None


def setup_of(test: str, view: dict[str, Any]) -> tuple[str, str, str, float, str]:
    """What makes two jobs' time steps and particle counts alike: test, rig, resolution, size factor and the
    contact law (Hertz's step is about 3x shorter than the linear springs')."""
    return (test, view["rig"], view["resolution"], round(float(view["scale_factor"]), 6),
            view.get("contact_law", "linear"))


def wall_time_estimate(session: Session, test: str, view: dict[str, Any], evaluator: str) -> dict[str, Any]:
    """``wall_time_s`` (None without a record), ``wall_time_range_s`` (the ratios' smallest and largest
    applied) and ``wall_time_basis`` (which finished jobs it rests on) for a job of ``view``
    (``engine.lab.cost.estimate_view``) run by ``evaluator``."""
    rows = session.execute(
        select(Job.spec, Job.wall_time_s).where(Job.status == JobStatus.SUCCEEDED, Job.evaluator == evaluator,
                                               Job.wall_time_s.is_not(None), Job.wall_time_s > 0)
        .order_by(Job.id.desc()).limit(RECENT_JOBS)).all()
    same, other = [], []
    target = setup_of(test, view)
    for spec, wall_s in rows:
        footprint = _footprint(json.dumps(spec, sort_keys=True))
        if footprint is None:
            continue
        setup, size = footprint
        (same if setup == target else other).append(wall_s / size)
    ratios, basis = (same, "the same set-up") if same else (other, "other set-ups (other time steps: rougher)")
    size = view["particles"] * view["simulated_time_s"]
    if not ratios or size <= 0:
        return {"wall_time_s": None, "wall_time_range_s": None,
                "wall_time_basis": f"no finished {evaluator} job on this service yet"}
    return {"wall_time_s": statistics.median(ratios) * size,
            "wall_time_range_s": [min(ratios) * size, max(ratios) * size],
            "wall_time_basis": f"{len(ratios)} finished {evaluator} job{'s' if len(ratios) > 1 else ''} of "
                               f"{basis} on this service"}
