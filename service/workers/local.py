"""A local worker: claim a job, run it with a heartbeat thread, acknowledge late.

The evaluator (``calibration.evaluator_registry.run_job``: the backend the job
names) runs in the worker's main thread; a heartbeat thread renews the
lease, stores the latest progress and picks up cancellation, which the evaluator
sees through ``should_cancel``. Engine kernels must return to Python (or release
the GIL) more often than ``lease_s`` or the heartbeat stalls and the job is
reclaimed elsewhere.
"""
from __future__ import annotations

import logging
import os
import socket
import threading
import time
import traceback
import uuid
from typing import Callable

from sqlalchemy.orm import Session, sessionmaker

from calibration.evaluator_registry import run_job
from engine.lab.spec import JobSpec
from service.config import Settings
from service.models.job import Job
from service.workers.errors import public_error
from service.queue import LeaseLost, claim_next, complete_job, finish_job, heartbeat, release_job
from service.vocabulary import JobStatus

log = logging.getLogger(__name__)
MAX_BACKOFF_S = 30.0  # longest wait between claim attempts while the database fails


def default_worker_id(kind: str = "local") -> str:
    return f"{kind}:{socket.gethostname()}:{os.getpid()}:{uuid.uuid4().hex[:6]}"


class _Heartbeat(threading.Thread):
    """Renews one job's lease every ``heartbeat_s`` and carries progress/cancel across."""

    def __init__(self, session_factory: sessionmaker[Session], job_id: int, worker_id: str, settings: Settings):
        super().__init__(name=f"heartbeat-{job_id}", daemon=True)
        self.session_factory, self.job_id, self.worker_id, self.settings = session_factory, job_id, worker_id, settings
        self.progress: tuple[float | None, str | None] = (None, None)
        self.cancel_requested = threading.Event()
        self.lease_lost = threading.Event()
        self.done = threading.Event()

    def beat(self) -> None:
        fraction, phase = self.progress
        with self.session_factory() as session:
            try:
                if heartbeat(session, self.job_id, self.worker_id, self.settings.lease_s, fraction, phase):
                    self.cancel_requested.set()
            except LeaseLost:
                self.lease_lost.set()

    def run(self) -> None:
        while not self.done.wait(self.settings.heartbeat_s):
            try:
                self.beat()
            except Exception:  # a transient DB error must not kill the heartbeat; the lease has slack
                log.exception("heartbeat for job %s failed", self.job_id)
            if self.lease_lost.is_set():
                return


def execute_claimed(session_factory: sessionmaker[Session], job: Job, worker_id: str, settings: Settings,
                    evaluate: Callable = run_job, stopping: threading.Event | None = None) -> str:
    """Run a job this worker has claimed; returns the status it ended in (or 'lost'/'released')."""
    beat = _Heartbeat(session_factory, job.id, worker_id, settings)
    stopping = stopping or threading.Event()

    def progress(fraction: float, phase: str) -> None:
        beat.progress = (fraction, phase)

    def should_cancel() -> bool:
        return beat.cancel_requested.is_set() or beat.lease_lost.is_set() or stopping.is_set()

    started = time.perf_counter()
    beat.start()
    try:
        spec = JobSpec.model_validate(job.spec)
        result = evaluate(job.evaluator, spec, progress, should_cancel)
    except BaseException as exc:  # noqa: BLE001 - the reason is stored, not swallowed
        beat.done.set()
        beat.join()
        elapsed = time.perf_counter() - started
        with session_factory() as session:
            if beat.lease_lost.is_set():
                return "lost"
            if beat.cancel_requested.is_set():
                finish_job(session, job.id, worker_id, JobStatus.CANCELLED, "cancelled while running", elapsed)
                return JobStatus.CANCELLED
            if stopping.is_set() or isinstance(exc, (KeyboardInterrupt, SystemExit)):
                release_job(session, job.id, worker_id)
                return "released"
            reason = public_error(exc)
            # the traceback is for the operator (this log), not for whoever reads the job
            log.warning("job %s failed: %s\n%s", job.id, reason, traceback.format_exc())
            finish_job(session, job.id, worker_id, JobStatus.FAILED, reason, elapsed)
            return JobStatus.FAILED
    beat.done.set()
    beat.join()
    with session_factory() as session:
        if complete_job(session, job.id, worker_id, result, time.perf_counter() - started):
            return JobStatus.SUCCEEDED
    log.warning("job %s finished after its lease was lost; result discarded (it runs elsewhere)", job.id)
    return "lost"


class Worker:
    """Claims and runs jobs until ``stop`` is set."""

    def __init__(self, session_factory: sessionmaker[Session], settings: Settings, worker_id: str | None = None,
                 evaluate: Callable = run_job):
        self.session_factory, self.settings, self.evaluate = session_factory, settings, evaluate
        self.worker_id = worker_id or default_worker_id()
        self.stop = threading.Event()

    def run_one(self) -> str | None:
        with self.session_factory() as session:
            job = claim_next(session, self.worker_id, self.settings.lease_s)
        if job is None:
            return None
        log.info("worker %s runs job %s (attempt %s)", self.worker_id, job.id, job.attempts)
        return execute_claimed(self.session_factory, job, self.worker_id, self.settings, self.evaluate, self.stop)

    def run(self, max_jobs: int | None = None) -> int:
        """Claim and run until stopped. When the database fails (unreachable, read-only, locked) the
        worker backs off, doubling its wait up to ``MAX_BACKOFF_S``, and logs one line per new reason
        or per minute, not a traceback every poll."""
        done, failures, last_reason, last_logged = 0, 0, None, 0.0
        while not self.stop.is_set() and (max_jobs is None or done < max_jobs):
            try:
                status = self.run_one()
            except Exception as exc:  # noqa: BLE001 - storage trouble: back off, say why, do not die
                from service.storage import describe

                failures += 1
                reason = describe(exc)
                wait = min(MAX_BACKOFF_S, self.settings.poll_interval_s * 2 ** min(failures, 16))
                if reason != last_reason or time.monotonic() - last_logged > 60:
                    log.error("worker %s cannot use the database (%s); retrying in %.1f s",
                              self.worker_id, reason, wait)
                    last_reason, last_logged = reason, time.monotonic()
                self.stop.wait(wait)
                continue
            if failures:
                log.warning("worker %s: database usable again after %d failed attempts", self.worker_id, failures)
                failures, last_reason = 0, None
            if status is None:
                self.stop.wait(self.settings.poll_interval_s)
            else:
                done += 1
        return done
