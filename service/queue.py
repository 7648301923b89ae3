"""The job queue: rows in ``jobs``, claimed with a lease, acknowledged late.

Semantics (Celery/RQ with ``acks_late``): a job counts as done only when its
result is committed in the same transaction as ``status='succeeded'``. A worker
holds a lease it must renew by heartbeat; when a lease expires (the worker died,
or hung) the job is queued again, up to ``max_attempts`` claims, then failed with
the reason kept. Every state change is a conditional ``UPDATE ... WHERE status=...``
whose row count says who won, so two workers never both own a job, on SQLite
(writes serialised by the file lock) and on PostgreSQL (row locks) alike.
"""
from __future__ import annotations

from datetime import timedelta
from typing import Any

from sqlalchemy import func, insert, literal, select, text, update
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm import Session

from calibration import evaluator_registry
from engine.lab.result import LabResult
from engine.lab.resolution import label
from engine.lab.spec import JobSpec
from service.config import Settings, get_settings
from service.errors import Conflict, Invalid, NotFound, TooMany
from service.models.base import utcnow
from service.models.job import Job
from service.vocabulary import JobOrigin, JobStatus
from service.limits import check_limits

CLAIM_CANDIDATES = 8  # queued ids tried per claim before giving up on this round


class LeaseLost(Exception):
    """The worker no longer owns the job (expired and reclaimed, or cancelled by shutdown)."""


def _settings(session: Session, settings: Settings | None) -> Settings:
    return settings or session.info.get("settings") or get_settings()


def _update(session: Session, job_id: int, where: list, values: dict[str, Any]) -> bool:
    stmt = update(Job).where(Job.id == job_id, *where).values(**values).execution_options(
        synchronize_session=False)
    return session.execute(stmt).rowcount == 1


def _spec_json(spec: JobSpec) -> dict[str, Any]:
    """The spec as stored. A preset job leaves out the unset resolution, rig and particles, so that it is
    stored as before they existed and an idempotent resubmission of a job stored then still matches it."""
    dumped = spec.model_dump(mode="json")
    return {k: v for k, v in dumped.items() if not (k in ("resolution", "rig", "particles") and v is None)}


# -- submission and reads (API side) -----------------------------------------------------------

def submit_job_ex(
    session: Session,
    spec: JobSpec,
    *,
    evaluator: str = evaluator_registry.DEFAULT.name,
    priority: int = 0,
    idempotency_key: str | None = None,
    client_id: str = "anonymous",
    campaign_id: int | None = None,
    max_attempts: int | None = None,
    owner: str | None = None,
    settings: Settings | None = None,
) -> tuple[Job, bool]:
    """Queue a job; returns ``(job, created)``. Commits. Same idempotency key -> same job."""
    cfg = _settings(session, settings)
    _check_evaluator(evaluator, spec)
    spec_json = _spec_json(spec)
    if idempotency_key is not None:
        existing = _by_key(session, client_id, idempotency_key)
        if existing is not None:
            return _replay(existing, spec_json, evaluator), False
    check_limits(spec, cfg)
    values = dict(
        status=JobStatus.QUEUED, evaluator=evaluator, test=spec.test, fidelity=label(spec.resolution, spec.fidelity), spec=spec_json,
        seed=spec.seed, priority=priority, attempts=0, max_attempts=max_attempts or cfg.max_attempts,
        cancel_requested=False, progress_fraction=0.0, idempotency_key=idempotency_key,
        client_id=client_id, owner=owner, campaign_id=campaign_id, created_at=utcnow(),
    )
    try:
        job_id = _insert_within_limit(session, values, cfg.max_queued_jobs_per_client)
        session.commit()
    except IntegrityError:
        # A concurrent submission with the same key won the unique index.
        session.rollback()
        existing = _by_key(session, client_id, idempotency_key) if idempotency_key else None
        if existing is None:
            raise
        return _replay(existing, spec_json, evaluator), False
    if job_id is None:
        session.rollback()
        unfinished = _unfinished(session, client_id)
        raise TooMany(f"client {client_id!r} already has {unfinished} unfinished jobs "
                      f"(limit {cfg.max_queued_jobs_per_client})", ["header", "X-Client-Id"])
    return get_job(session, job_id), True


def _check_evaluator(name: str, spec: JobSpec) -> None:
    """A registered backend that covers the spec's test, or a 422 naming the field (the API's schema
    checks the name too, but campaigns and schedules queue through here without it)."""
    try:
        evaluator_registry.get(name).check_test(spec.test)
    except evaluator_registry.UnknownEvaluator as exc:
        raise Invalid(str(exc), "evaluator") from None
    except evaluator_registry.UncoveredTest as exc:
        raise Invalid(str(exc), "test") from None


def _unfinished(session: Session, client_id: str) -> int:
    return int(session.scalar(select(func.count(Job.id)).where(
        Job.client_id == client_id, Job.status.in_(JobStatus.unfinished()))) or 0)


def _insert_within_limit(session: Session, values: dict[str, Any], limit: int) -> int | None:
    """Insert the job only if its client has fewer than ``limit`` unfinished jobs; the new id, or None.

    Atomic: the count and the insert are one statement (``INSERT ... SELECT ... WHERE count < limit``),
    which SQLite runs under its single write lock, so a burst of submissions admits exactly ``limit``
    (a count, then an insert, admitted 4 and 7 of a limit of 3). PostgreSQL runs concurrent statements
    on snapshots, so there the client's transaction-scoped advisory lock serialises them first.
    """
    if session.get_bind().dialect.name == "postgresql":
        session.execute(text("SELECT pg_advisory_xact_lock(hashtext(:c))"), {"c": values["client_id"]})
    table = Job.__table__
    columns = list(values)
    unfinished = (select(func.count()).select_from(table)
                  .where(table.c.client_id == values["client_id"], table.c.status.in_(JobStatus.unfinished()))
                  .scalar_subquery())
    source = select(*[literal(values[c], type_=table.c[c].type) for c in columns]).where(unfinished < limit)
    result = session.execute(insert(table).from_select(columns, source).returning(table.c.id))
    return result.scalar()


def submit_job(session: Session, spec: JobSpec, **kwargs) -> Job:
    return submit_job_ex(session, spec, **kwargs)[0]


def _by_key(session: Session, client_id: str, key: str) -> Job | None:
    return session.scalar(select(Job).where(Job.client_id == client_id, Job.idempotency_key == key))


def _replay(existing: Job, spec_json: dict, evaluator: str) -> Job:
    if existing.spec != spec_json or existing.evaluator != evaluator:
        raise Conflict("idempotency key already used for a different job", "idempotency_key")
    return existing


def get_job(session: Session, job_id: int) -> Job:
    job = session.get(Job, job_id, populate_existing=True)
    if job is None:
        raise NotFound(f"no job {job_id}", ["path", "job_id"])
    return job


def list_jobs(session: Session, *, status: str | None = None, test: str | None = None,
              campaign_id: int | None = None, evaluator: str | None = None,
              origin: JobOrigin = JobOrigin.ALL, limit: int = 100, offset: int = 0) -> tuple[list[Job], int]:
    where = []
    if origin == JobOrigin.DIRECT:
        where.append(Job.campaign_id.is_(None))
    elif origin == JobOrigin.CAMPAIGN:
        where.append(Job.campaign_id.is_not(None))
    if status is not None:
        where.append(Job.status == status)
    if test is not None:
        where.append(Job.test == test)
    if campaign_id is not None:
        where.append(Job.campaign_id == campaign_id)
    if evaluator is not None:
        where.append(Job.evaluator == evaluator)
    total = session.scalar(select(func.count(Job.id)).where(*where))
    rows = session.scalars(select(Job).where(*where).order_by(Job.id.desc()).limit(limit).offset(offset)).all()
    return list(rows), int(total or 0)


def cancel_job(session: Session, job_id: int) -> Job:
    """Queued -> cancelled now; running -> flag the worker sees at its next heartbeat."""
    for _ in range(3):  # the job may be claimed between our read and our write
        job = get_job(session, job_id)
        if job.status == JobStatus.QUEUED:
            done = _update(session, job_id, [Job.status == JobStatus.QUEUED],
                           {"status": JobStatus.CANCELLED, "cancel_requested": True, "finished_at": utcnow(),
                            "error": "cancelled before it started"})
        elif job.status == JobStatus.RUNNING:
            done = _update(session, job_id, [Job.status == JobStatus.RUNNING], {"cancel_requested": True})
        else:
            raise Conflict(f"job {job_id} is already {job.status}", ["path", "job_id"])
        session.commit()
        if done:
            return get_job(session, job_id)
    raise Conflict(f"job {job_id} changed state while cancelling; try again", ["path", "job_id"])


def retry_job(session: Session, job_id: int) -> Job:
    """Failed or cancelled -> queued again, same id, fresh attempt budget."""
    job = get_job(session, job_id)
    done = _update(session, job_id, [Job.status.in_(JobStatus.unsuccessful())], {
        "status": JobStatus.QUEUED, "attempts": 0, "cancel_requested": False, "lease_owner": None,
        "lease_expires_at": None, "heartbeat_at": None, "progress_fraction": 0.0, "progress_phase": None,
        "result": None, "error": None, "started_at": None, "finished_at": None, "wall_time_s": None,
    })
    session.commit()
    if not done:
        raise Conflict(f"only failed or cancelled jobs can be retried; job {job_id} is {job.status}",
                       ["path", "job_id"])
    return get_job(session, job_id)


def queue_counts(session: Session) -> dict[str, int]:
    rows = session.execute(select(Job.status, func.count(Job.id)).group_by(Job.status)).all()
    return {status: int(n) for status, n in rows}


# -- worker side ---------------------------------------------------------------------------------

def reclaim_expired(session: Session) -> int:
    """Requeue (or fail, or finish cancelling) running jobs whose lease has run out."""
    now = utcnow()
    expired = session.execute(
        select(Job.id, Job.attempts, Job.max_attempts, Job.cancel_requested, Job.lease_owner,
               Job.lease_expires_at).where(Job.status == JobStatus.RUNNING, Job.lease_expires_at < now)
    ).all()
    changed = 0
    for job_id, attempts, max_attempts, cancel_requested, owner, expires in expired:
        reason = f"attempt {attempts}: lease of worker {owner} expired at {expires.isoformat()}Z"
        if cancel_requested:
            values = {"status": JobStatus.CANCELLED, "finished_at": now, "error": f"cancelled; {reason}"}
        elif attempts >= max_attempts:
            values = {"status": JobStatus.FAILED, "finished_at": now,
                      "error": f"lost its worker {attempts} times (max_attempts={max_attempts}); {reason}"}
        else:
            values = {"status": JobStatus.QUEUED, "error": reason}
        values.update(lease_owner=None, lease_expires_at=None)
        changed += _update(session, job_id, [Job.status == JobStatus.RUNNING, Job.lease_owner == owner,
                                             Job.lease_expires_at == expires], values)
    session.commit()
    return changed


def claim_next(session: Session, worker_id: str, lease_s: float) -> Job | None:
    """Claim the highest-priority, oldest queued job for ``worker_id``, or None."""
    reclaim_expired(session)
    candidates = session.scalars(
        select(Job.id).where(Job.status == JobStatus.QUEUED).order_by(Job.priority.desc(), Job.id)
        .limit(CLAIM_CANDIDATES)
    ).all()
    session.commit()  # end the read transaction so the write below waits on the lock, not a stale snapshot
    for job_id in candidates:
        now = utcnow()
        won = _update(session, job_id, [Job.status == JobStatus.QUEUED], {
            "status": JobStatus.RUNNING, "lease_owner": worker_id, "lease_expires_at": now + timedelta(seconds=lease_s),
            "heartbeat_at": now, "attempts": Job.attempts + 1, "started_at": now, "progress_fraction": 0.0,
            "progress_phase": "claimed",
        })
        session.commit()
        if won:
            return get_job(session, job_id)
    return None


def _owned(worker_id: str) -> list:
    return [Job.status == JobStatus.RUNNING, Job.lease_owner == worker_id]


def heartbeat(session: Session, job_id: int, worker_id: str, lease_s: float,
              fraction: float | None = None, phase: str | None = None) -> bool:
    """Extend the lease and store progress; returns whether cancellation was requested."""
    now = utcnow()
    values: dict[str, Any] = {"lease_expires_at": now + timedelta(seconds=lease_s), "heartbeat_at": now}
    if fraction is not None:
        values["progress_fraction"] = min(1.0, max(0.0, float(fraction)))
    if phase is not None:
        values["progress_phase"] = str(phase)[:64]
    if not _update(session, job_id, _owned(worker_id), values):
        session.commit()
        raise LeaseLost(f"job {job_id} is no longer leased to {worker_id}")
    cancel = session.scalar(select(Job.cancel_requested).where(Job.id == job_id))
    session.commit()
    return bool(cancel)


def complete_job(session: Session, job_id: int, worker_id: str, result: LabResult, wall_time_s: float) -> bool:
    """Store the result and mark success in one transaction; False if the lease was lost.

    The error is cleared: a job re-queued after a lost lease kept "attempt 1: ..." next to its result, which
    read as a failure; the attempt count still says it took more than one."""
    done = _update(session, job_id, _owned(worker_id), {
        "status": JobStatus.SUCCEEDED, "result": result.model_dump(mode="json"), "finished_at": utcnow(),
        "error": None,
        "engine_version": result.provenance.engine_version, "wall_time_s": wall_time_s,
        "progress_fraction": 1.0, "progress_phase": "done", "lease_expires_at": None,
    })
    session.commit()
    return done


def finish_job(session: Session, job_id: int, worker_id: str, status: JobStatus, error: str,
               wall_time_s: float | None = None) -> bool:
    """End a job the worker owns as failed or cancelled, keeping the reason."""
    assert status in JobStatus.unsuccessful()
    done = _update(session, job_id, _owned(worker_id), {
        "status": status, "error": error[:20000], "finished_at": utcnow(), "wall_time_s": wall_time_s,
        "lease_expires_at": None,
    })
    session.commit()
    return done


def release_job(session: Session, job_id: int, worker_id: str) -> bool:
    """Hand an unfinished job back (graceful shutdown): queued again, this attempt not counted."""
    done = _update(session, job_id, _owned(worker_id), {
        "status": JobStatus.QUEUED, "lease_owner": None, "lease_expires_at": None, "attempts": Job.attempts - 1,
        "progress_fraction": 0.0, "progress_phase": None,
    })
    session.commit()
    return done


def requeue_job(session: Session, job_id: int, worker_id: str, reason: str) -> bool:
    """The executor lost this attempt (its Dask worker or scheduler is gone): queued again with the
    attempt counted, or failed once ``max_attempts`` claims are used up. Only the owner can do it."""
    job = get_job(session, job_id)
    if job.status != JobStatus.RUNNING or job.lease_owner != worker_id:
        session.commit()
        return False
    if job.attempts >= job.max_attempts:
        values = {"status": JobStatus.FAILED, "finished_at": utcnow(),
                  "error": f"lost its executor {job.attempts} times (max_attempts={job.max_attempts}); {reason}"}
    else:
        values = {"status": JobStatus.QUEUED, "error": f"attempt {job.attempts}: {reason}", "progress_fraction": 0.0,
                  "progress_phase": None}
    done = _update(session, job_id, _owned(worker_id), {**values, "lease_owner": None, "lease_expires_at": None})
    session.commit()
    return done


def count_attempt(session: Session, job_id: int, worker_id: str) -> int | None:
    """One more attempt of a job the executor re-ran by itself (Dask re-runs a task whose worker died);
    returns the attempts now counted, or None if the job is no longer this owner's."""
    done = _update(session, job_id, _owned(worker_id), {"attempts": Job.attempts + 1})
    session.commit()
    return get_job(session, job_id).attempts if done else None
