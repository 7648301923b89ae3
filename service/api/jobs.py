"""DEM job endpoints: submit, list, status/progress, result and curves, cancel, retry."""
from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Depends, Header, Query, Request, Response, status
from fastapi import Path as PathParam
from pydantic import BaseModel, Field, ValidationError

from calibration.evaluator_registry import DEFAULT, EvaluatorName
from engine.lab.bounds import ID_MAX, MAX_SEED
from engine.lab.plausibility import options_warnings, parameter_warnings
from engine.lab.cost import estimate_view
from engine.lab.registry import BATTERY, JobTestName
from engine.lab.resolution import ResolutionIn
from engine.lab.rigs import Rig
from engine.lab.spec import STRICT_INPUT, Fidelity, JobSpec, MicroParameters, TestOptions, WholeNumber
from engine.lab.whole_number import bounded_whole_number
from engine.particles.description import Particles
from service import queue
from service.api.jsonsafe import json_safe
from service.api.openapi import errors
from service.api.params import PRIORITY_MAX, PRIORITY_MIN, JobId, JobLimit, Offset
from service.api.responses.common import CostEstimate, typed
from service.api.responses.jobs import Curve, CurveIndex, JobList, JobOut, JobResult, Progress
from service.db import DbSession
from service.errors import Conflict, Invalid, NotFound
from service.models.job import Job
from service.ownership import Caller, caller, owner_of
from service.security import client_id
from service.wall_estimate import wall_time_estimate
from service.vocabulary import JobOrigin, JobStatus
from service.workers.errors import scrub

router = APIRouter(prefix="/jobs", tags=["jobs"])


CampaignId = bounded_whole_number(1, ID_MAX)
AttemptCount = bounded_whole_number(1, 20)


class JobSubmit(BaseModel):
    """A single test or a battery: the job spec plus how to queue it."""

    model_config = STRICT_INPUT

    test: JobTestName = BATTERY
    fidelity: Fidelity = "screening"
    seed: WholeNumber = Field(0, ge=0, le=MAX_SEED, description="random seed; same seed and thread count, same result")
    parameters: MicroParameters = Field(default_factory=MicroParameters)
    options: TestOptions = Field(default_factory=TestOptions)
    evaluator: EvaluatorName = Field(DEFAULT.name, description="the backend the job runs on (GET /api/v1/evaluators)")
    priority: WholeNumber = Field(0, ge=PRIORITY_MIN, le=PRIORITY_MAX, description="higher runs first")
    idempotency_key: str | None = Field(None, min_length=1, max_length=200,
                                        description="resubmitting the same key returns the same job")
    # the bounds inside the union: on a nullable WholeNumber (a BeforeValidator) pydantic published them as
    # "ge"/"le", which JSON Schema ignores, so schema-valid clients sent 2037 replicates and were refused
    campaign_id: CampaignId | None = None
    max_attempts: AttemptCount | None = Field(None, description="claims before a lost job fails")
    resolution: ResolutionIn | None = Field(None, description=JobSpec.model_fields["resolution"].description)
    rig: Rig | None = Field(None, description=JobSpec.model_fields["rig"].description)
    particles: Particles | None = Field(None, description=JobSpec.model_fields["particles"].description)

    def spec(self) -> JobSpec:
        """The job spec; its own cross-field checks (a resolution without its rig) are 422s naming the field."""
        try:
            return JobSpec.model_validate({
                "test": self.test, "fidelity": self.fidelity, "seed": self.seed, "parameters": self.parameters,
                "options": self.options, "resolution": self.resolution, "rig": self.rig, "particles": self.particles})
        except ValidationError as exc:
            first = exc.errors(include_url=False)[0]
            raise Invalid(str(first["msg"]).removeprefix("Value error, "), ".".join(str(p) for p in first["loc"])) from None


def job_out(job: Job) -> JobOut:
    return JobOut(
        id=job.id, status=job.status, evaluator=job.evaluator, test=job.test, fidelity=job.fidelity,
        seed=job.seed, priority=job.priority, attempts=job.attempts, max_attempts=job.max_attempts,
        progress=Progress(fraction=job.progress_fraction, phase=job.progress_phase),
        cancel_requested=job.cancel_requested, error=None if job.error is None else scrub(job.error),
        engine_version=job.engine_version,
        wall_time_s=job.wall_time_s, created_at=job.created_at, started_at=job.started_at,
        finished_at=job.finished_at, heartbeat_at=job.heartbeat_at, lease_owner=job.lease_owner,
        lease_expires_at=job.lease_expires_at, idempotency_key=job.idempotency_key, client_id=job.client_id,
        owner=job.owner,
        campaign_id=job.campaign_id, result_available=job.status == JobStatus.SUCCEEDED and job.result is not None,
        spec=json_safe(job.spec),
        warnings=parameter_warnings((job.spec or {}).get("parameters") or {})
        + options_warnings((job.spec or {}).get("options") or {}),
    )


def _result(job: Job) -> dict[str, Any]:
    if job.status != JobStatus.SUCCEEDED or job.result is None:
        raise Conflict(f"job {job.id} is {job.status}; a result exists only for succeeded jobs", ["path", "job_id"])
    return job.result


@router.post("", response_model=JobOut, status_code=status.HTTP_201_CREATED,
             summary="Queue a single test or a battery",
             responses={200: {"description": "idempotent replay: the job already queued with this key",
                              "model": JobOut},
                        **errors(403, 409, 422, 429, c403="campaign_id names another user's campaign",
                                 c409="idempotency key reused with a different body",
                                 c422="invalid spec or over a limit (field named, with the limit and estimate)")})
def submit(body: JobSubmit, request: Request, response: Response, session: DbSession,
           client: str = Depends(client_id), who: Caller = Depends(caller), owner: str | None = Depends(owner_of),
           idempotency_key: str | None = Header(None, alias="Idempotency-Key", max_length=200)) -> JobOut:
    if body.campaign_id is not None:  # a job filed under a campaign is a change to that campaign
        from service.models.campaign import Campaign

        campaign = session.get(Campaign, body.campaign_id)
        if campaign is not None:
            who.require(campaign.owner, f"campaign {campaign.id}", "campaign_id")
    job, created = queue.submit_job_ex(
        session, body.spec(), evaluator=body.evaluator, priority=body.priority,
        idempotency_key=body.idempotency_key or idempotency_key, client_id=client,
        campaign_id=body.campaign_id, max_attempts=body.max_attempts, owner=owner,
    )
    if not created:
        response.status_code = status.HTTP_200_OK
    response.headers["Location"] = str(request.url_for("get_job", job_id=job.id))
    out = job_out(job)
    spec = JobSpec.model_validate(job.spec)
    view = estimate_view(spec)
    out.estimate = CostEstimate(**view, **wall_time_estimate(session, spec.test, view, job.evaluator))
    return out


@router.get("", response_model=JobList, summary="List jobs, newest first (by id), filtered; a page and the total")
def list_jobs(session: DbSession, status_: JobStatus | None = Query(None, alias="status"),
              test: JobTestName | None = None, campaign_id: int | None = Query(None, ge=1, le=ID_MAX),
              evaluator: EvaluatorName | None = None,
              origin: JobOrigin = Query(JobOrigin.ALL, description="direct: jobs submitted without a campaign; "
                                        "campaign: the batteries campaigns queued; all: both"),
              limit: JobLimit = 100, offset: Offset = 0) -> JobList:
    rows, total = queue.list_jobs(session, status=status_, test=test, campaign_id=campaign_id,
                                  evaluator=evaluator, origin=origin, limit=limit, offset=offset)
    return JobList(items=[job_out(j) for j in rows], total=total, limit=limit, offset=offset)


@router.get("/{job_id}", response_model=JobOut, name="get_job", summary="Status and progress")
def get_job(job_id: JobId, session: DbSession) -> JobOut:
    return job_out(queue.get_job(session, job_id))


@router.get("/{job_id}/result", summary="The result record (properties, provenance, optionally curves)",
            **typed(JobResult),
            responses=errors(409, c409="the job has not succeeded (no result)"))
def get_result(session: DbSession, job_id: JobId, include_curves: bool = True) -> dict:
    record = dict(_result(queue.get_job(session, job_id)))
    if not include_curves:
        record.pop("curves", None)
    return json_safe(record)


@router.get("/{job_id}/curves", summary="Names of the result's curves, their columns and lengths (no data)",
            **typed(dict[str, CurveIndex]),
            responses=errors(409, c409="the job has not succeeded (no result)"))
def get_curves(job_id: JobId, session: DbSession) -> dict:
    """An index, small whatever the run: the data is at ``/curves/{name}`` (or in ``/result``)."""
    curves = _result(queue.get_job(session, job_id)).get("curves", {})
    return {name: {"columns": sorted(columns), "points": max((len(v) for v in columns.values()), default=0)}
            for name, columns in curves.items()}


@router.get("/{job_id}/curves/{name}", summary="One curve: equal-length SI columns", **typed(Curve),
            responses=errors(409, c409="the job has not succeeded (no result)"))
def get_curve(session: DbSession, job_id: JobId, name: str = PathParam(..., max_length=200)) -> dict:
    curves = _result(queue.get_job(session, job_id)).get("curves", {})
    if name not in curves:
        raise NotFound(f"job {job_id} has no curve {name!r}; it has {sorted(curves)}", ["path", "name"])
    return json_safe(curves[name])


@router.post("/{job_id}/cancel", response_model=JobOut, summary="Cancel a queued job, or ask a running one to stop",
             responses={202: {"description": "running: cancellation requested, the worker stops at its next check"},
                        **errors(403, 409, c403="another user's job", c409="already finished")})
def cancel(job_id: JobId, response: Response, session: DbSession, who: Caller = Depends(caller)) -> JobOut:
    who.require(queue.get_job(session, job_id).owner, f"job {job_id}", ["path", "job_id"])
    job = queue.cancel_job(session, job_id)
    if job.status == JobStatus.RUNNING:
        response.status_code = status.HTTP_202_ACCEPTED
    return job_out(job)


@router.post("/{job_id}/retry", response_model=JobOut, summary="Queue a failed or cancelled job again",
             responses=errors(403, 409, c403="another user's job", c409="the job is not failed or cancelled"))
def retry(job_id: JobId, session: DbSession, who: Caller = Depends(caller)) -> JobOut:
    who.require(queue.get_job(session, job_id).owner, f"job {job_id}", ["path", "job_id"])
    return job_out(queue.retry_job(session, job_id))
