"""Queue semantics on a real database (a SQLite file, and PostgreSQL): claims, leases, retries, cancellation, late ack."""
from __future__ import annotations

import math
import threading
import time

import pytest

from calibration.evaluator_registry import run_job
from engine.lab.result import Cancelled
from engine.lab.spec import JobSpec
from service import queue
from service.errors import Conflict, Invalid, TooMany
from service.models.job import Job
from service.workers.local import Worker

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)


def _submit(sf, n: int = 1, **kwargs) -> list[int]:
    with sf() as s:
        return [queue.submit_job(s, JobSpec(seed=i), evaluator="analytic", **kwargs).id for i in range(n)]


def _job(sf, job_id: int) -> Job:
    with sf() as s:
        return queue.get_job(s, job_id)


def test_claim_takes_highest_priority_then_oldest(session_factory):
    low = _submit(session_factory, 2)
    high = _submit(session_factory, 1, priority=5)
    with session_factory() as s:
        order = [queue.claim_next(s, "w", 30).id for _ in range(3)]
        assert queue.claim_next(s, "w", 30) is None
    assert order == [high[0], low[0], low[1]]


def test_concurrent_claimers_never_share_a_job(session_factory):
    ids = set(_submit(session_factory, 40))
    claimed: list[tuple[str, int]] = []
    lock = threading.Lock()

    def claimer(name: str) -> None:
        with session_factory() as s:
            while (job := queue.claim_next(s, name, 30)) is not None:
                with lock:
                    claimed.append((name, job.id))

    threads = [threading.Thread(target=claimer, args=(f"w{i}",)) for i in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    claimed_ids = [job_id for _, job_id in claimed]
    assert sorted(claimed_ids) == sorted(ids)  # each exactly once
    with session_factory() as s:
        for name, job_id in claimed:
            assert queue.get_job(s, job_id).lease_owner == name


def test_expired_lease_requeues_then_fails_with_reason(session_factory):
    (job_id,) = _submit(session_factory, 1, max_attempts=2)
    with session_factory() as s:
        assert queue.claim_next(s, "dead-1", 0.05).id == job_id
        time.sleep(0.1)
        assert queue.claim_next(s, "dead-2", 0.05).id == job_id  # reclaimed: attempt 2
        job = queue.get_job(s, job_id)
        assert job.attempts == 2 and "dead-1" in job.error
        time.sleep(0.1)
        assert queue.claim_next(s, "w", 30) is None  # budget spent: failed, not requeued
        job = queue.get_job(s, job_id)
    assert job.status == "failed"
    assert "max_attempts=2" in job.error and "dead-2" in job.error


def test_cancel_requested_on_a_dead_workers_job_ends_cancelled(session_factory):
    (job_id,) = _submit(session_factory, 1)
    with session_factory() as s:
        queue.claim_next(s, "dead", 0.05)
        queue.cancel_job(s, job_id)
        time.sleep(0.1)
        assert queue.claim_next(s, "w", 30) is None  # not run again
        job = queue.get_job(s, job_id)
    assert job.status == "cancelled" and "dead" in job.error


def test_heartbeat_extends_lease_and_stores_progress(session_factory):
    (job_id,) = _submit(session_factory, 1)
    with session_factory() as s:
        queue.claim_next(s, "w", 0.3)
        for _ in range(4):
            time.sleep(0.15)
            assert queue.heartbeat(s, job_id, "w", 0.3, 0.25, "filling") is False
        assert queue.reclaim_expired(s) == 0
        job = queue.get_job(s, job_id)
    assert job.status == "running" and job.progress_fraction == 0.25 and job.progress_phase == "filling"


def test_stale_worker_cannot_heartbeat_or_complete(session_factory):
    (job_id,) = _submit(session_factory, 1)
    with session_factory() as s:
        queue.claim_next(s, "slow", 0.05)
        time.sleep(0.1)
        queue.claim_next(s, "fresh", 30)
        with pytest.raises(queue.LeaseLost):
            queue.heartbeat(s, job_id, "slow", 30)
        from calibration.evaluator_registry import run_job

        result = run_job("analytic", JobSpec())
        assert queue.complete_job(s, job_id, "slow", result, 1.0) is False
        job = queue.get_job(s, job_id)
        assert job.status == "running" and job.result is None and job.lease_owner == "fresh"
        assert queue.complete_job(s, job_id, "fresh", result, 1.0) is True
        job = queue.get_job(s, job_id)
    assert job.status == "succeeded" and job.result["test"] == "battery"
    assert job.engine_version == result.provenance.engine_version


def test_cancel_queued_and_running(session_factory):
    running, queued = _submit(session_factory, 2)
    with session_factory() as s:
        assert queue.claim_next(s, "w", 30).id == running  # oldest first
        assert queue.cancel_job(s, queued).status == "cancelled"
        job = queue.cancel_job(s, running)
        assert job.status == "running" and job.cancel_requested
        assert queue.heartbeat(s, running, "w", 30) is True
        with pytest.raises(Conflict):
            queue.cancel_job(s, queued)
        assert queue.retry_job(s, queued).status == "queued"
        with pytest.raises(Conflict):
            queue.retry_job(s, running)


def test_idempotency_key_under_concurrency(session_factory):
    ids: list[int] = []

    def submit() -> None:
        with session_factory() as s:
            ids.append(queue.submit_job(s, JobSpec(seed=7), evaluator="analytic", idempotency_key="same").id)

    threads = [threading.Thread(target=submit) for _ in range(10)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(set(ids)) == 1
    with session_factory() as s:
        assert queue.list_jobs(s)[1] == 1
        with pytest.raises(Conflict):
            queue.submit_job(s, JobSpec(seed=8), evaluator="analytic", idempotency_key="same")
        # keys are per client
        other = queue.submit_job(s, JobSpec(seed=7), evaluator="analytic", idempotency_key="same", client_id="b")
        assert other.id != ids[0]


def test_limits(session_factory, settings):
    limited = settings.model_copy(update={"max_queued_jobs_per_client": 2})
    with session_factory() as s:
        for i in range(2):
            queue.submit_job(s, JobSpec(seed=i), evaluator="analytic", settings=limited)
        with pytest.raises(TooMany):
            queue.submit_job(s, JobSpec(seed=3), evaluator="analytic", settings=limited)
        queue.submit_job(s, JobSpec(seed=3), evaluator="analytic", settings=limited, client_id="other")
        with pytest.raises(Invalid) as err:
            queue.submit_job(s, JobSpec(parameters={"particle_radius_m": 0.002}), settings=settings, client_id="x")
        assert err.value.loc() == ["body", "parameters", "particle_radius_m"]
        with pytest.raises(Invalid) as err:
            queue.submit_job(s, JobSpec(options={"speed_factor": 0.001}), settings=settings, client_id="x")
        assert err.value.loc() == ["body", "options", "speed_factor"]
        with pytest.raises(Invalid):
            queue.submit_job(s, JobSpec(), evaluator="python", settings=settings, client_id="x")


def test_worker_runs_reports_progress_and_acknowledges_late(session_factory, settings):
    (job_id,) = _submit(session_factory, 1)
    seen_phases: list[str] = []

    def slow_analytic(evaluator, spec, progress, should_cancel):
        from calibration.evaluator_registry import run_job

        for i in range(5):
            progress(i / 5, "shearing")
            time.sleep(0.1)
            if i == 3:
                seen_phases.append(_job(session_factory, job_id).progress_phase)
                assert _job(session_factory, job_id).status == "running"  # no result before the end
        return run_job(evaluator, spec)

    worker = Worker(session_factory, settings, "w-test", evaluate=slow_analytic)
    assert worker.run_one() == "succeeded"
    job = _job(session_factory, job_id)
    assert job.status == "succeeded" and job.progress_fraction == 1.0 and job.wall_time_s >= 0.5
    assert seen_phases == ["shearing"]
    assert worker.run_one() is None


def test_a_result_holding_nan_and_infinity_is_stored_and_read_back(session_factory, settings, client):
    """A diverged curve point is NaN or infinite. PostgreSQL's json type refuses those tokens, so there the
    job could not be completed (the UPDATE failed, the job with it); stored through service.json_columns,
    the worker's result reads back as it was on both backends, and the API shows the points as null."""
    (job_id,) = _submit(session_factory, 1)
    diverged: list[tuple[str, str]] = []

    def evaluate(evaluator, spec, progress, should_cancel):
        result = run_job(evaluator, spec)
        name = next(iter(result.curves))
        column = next(iter(result.curves[name]))
        result.curves[name][column][:3] = [math.nan, math.inf, -math.inf]
        result.properties[0].value = math.nan
        diverged.append((name, column))
        return result

    assert Worker(session_factory, settings, "w-nan", evaluate=evaluate).run_one() == "succeeded"
    ((name, column),) = diverged
    stored = _job(session_factory, job_id).result
    first = stored["curves"][name][column][:3]
    assert math.isnan(first[0]) and first[1] == math.inf and first[2] == -math.inf
    assert math.isnan(stored["properties"][0]["value"])
    shown = client.get(f"/api/v1/jobs/{job_id}/result")
    assert shown.status_code == 200
    assert shown.json()["properties"][0]["value"] is None


def test_worker_failure_keeps_reason(session_factory, settings):
    (job_id,) = _submit(session_factory, 1)

    def broken(*_args):
        raise ValueError("contact law diverged at step 12")

    assert Worker(session_factory, settings, evaluate=broken).run_one() == "failed"
    job = _job(session_factory, job_id)
    assert job.status == "failed" and "contact law diverged at step 12" in job.error
    assert job.attempts == 1  # deterministic failures are not retried


def test_cancellation_reaches_running_job(session_factory, settings):
    (job_id,) = _submit(session_factory, 1)
    started = threading.Event()

    def until_cancelled(evaluator, spec, progress, should_cancel):
        started.set()
        deadline = time.monotonic() + 20
        while time.monotonic() < deadline:
            if should_cancel():
                raise Cancelled("stopped")
            time.sleep(0.02)
        raise AssertionError("cancellation never arrived")

    worker = Worker(session_factory, settings, evaluate=until_cancelled)
    outcome: list[str] = []
    thread = threading.Thread(target=lambda: outcome.append(worker.run_one()))
    thread.start()
    assert started.wait(10)
    with session_factory() as s:
        queue.cancel_job(s, job_id)
    thread.join(20)
    assert outcome == ["cancelled"]
    assert _job(session_factory, job_id).status == "cancelled"


def test_stopping_worker_hands_job_back(session_factory, settings):
    (job_id,) = _submit(session_factory, 1)
    worker = Worker(session_factory, settings)

    def until_stopped(evaluator, spec, progress, should_cancel):
        worker.stop.set()  # as SIGTERM would
        assert should_cancel()
        raise Cancelled("shutdown")

    worker.evaluate = until_stopped
    assert worker.run_one() == "released"
    job = _job(session_factory, job_id)
    assert job.status == "queued" and job.attempts == 0 and job.lease_owner is None
