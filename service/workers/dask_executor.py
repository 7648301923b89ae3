"""Dask distributed executor: a dispatcher claims jobs and runs them on a Dask cluster.

The dispatcher, not the Dask worker, owns each job's lease: it heartbeats for
every job in flight, so queue semantics are the same as with local workers (a
dead dispatcher's jobs are reclaimed when their leases run out). Dask workers
never touch the database: progress and cancellation cross through two small Dask
``Variable``s per job.

Recovery (issue 13): the dispatcher renews a lease only while the cluster can run
the job. When no Dask worker is alive, it requeues its jobs (attempt counted) and
claims no more until one is; when Dask re-runs a task whose worker died, the
re-run counts as an attempt; when the scheduler is unreachable (any outage, longer
than the client's reconnect window included), it drops the client, requeues its
jobs, reports itself unhealthy (``/health`` answers 503) and reconnects with
back-off, logging one line per new reason instead of a traceback per round.
"""
from __future__ import annotations

import logging
import threading
import time
import traceback
from dataclasses import dataclass, field

from sqlalchemy.orm import Session, sessionmaker

from engine.lab.result import LabResult
from service.workers.errors import public_error
from service.config import Settings
from service.queue import (LeaseLost, claim_next, complete_job, count_attempt, finish_job, heartbeat, release_job,
                           requeue_job)
from service.vocabulary import JobStatus
from service.workers.local import default_worker_id

log = logging.getLogger(__name__)
POLL_REMOTE_S = 1.0  # how often a task asks the scheduler about cancellation / reports progress


def _names(job_id: int, attempt: int) -> tuple[str, str]:
    return f"demcal-progress-{job_id}-{attempt}", f"demcal-cancel-{job_id}-{attempt}"


def run_on_dask(evaluator: str, spec_json: dict, job_id: int, attempt: int) -> dict:
    """The Dask task: evaluate one spec; returns the LabResult as JSON-able data."""
    from distributed import Variable

    from engine.lab.spec import JobSpec
    from calibration.evaluator_registry import run_job

    progress_name, cancel_name = _names(job_id, attempt)
    progress_var, cancel_var = Variable(progress_name), Variable(cancel_name)
    last = {"progress": 0.0, "cancel": 0.0, "cancelled": False}

    def progress(fraction: float, phase: str) -> None:
        now = time.monotonic()
        if now - last["progress"] >= POLL_REMOTE_S:
            last["progress"] = now
            progress_var.set([float(fraction), str(phase)])

    def should_cancel() -> bool:
        now = time.monotonic()
        if not last["cancelled"] and now - last["cancel"] >= POLL_REMOTE_S:
            last["cancel"] = now
            last["cancelled"] = bool(cancel_var.get(timeout=5))
        return last["cancelled"]

    return run_job(evaluator, JobSpec.model_validate(spec_json), progress, should_cancel).model_dump(mode="json")


@dataclass
class _InFlight:
    job_id: int
    attempt: int
    future: object
    started: float = field(default_factory=time.perf_counter)
    cancel_requested: bool = False
    dask_worker: str | None = None  # the Dask worker last seen processing the task


MAX_BACKOFF_S = 30.0


class ClusterUnavailable(Exception):
    """The scheduler cannot be reached (or the client gave up reconnecting)."""


class DaskDispatcher:
    """Keeps the Dask cluster busy with claimed jobs and writes their results back."""

    def __init__(self, session_factory: sessionmaker[Session], settings: Settings, scheduler,
                 capacity: int | None = None):
        self.session_factory, self.settings = session_factory, settings
        self.scheduler, self.capacity = scheduler, capacity
        self.worker_id = default_worker_id("dask")
        self.stop = threading.Event()
        self.inflight: dict[int, _InFlight] = {}
        self._client = None
        self.healthy = False  # True once connected; False while the cluster cannot be used
        self.problem: str | None = "not connected yet"

    # -- the connection ------------------------------------------------------------------------------

    @property
    def client(self):
        if self._client is None:
            if hasattr(self.scheduler, "submit"):
                self._client = self.scheduler
            else:
                from distributed import Client

                try:
                    self._client = Client(self.scheduler, timeout=self.settings.dask_connect_timeout_s,
                                          set_as_default=False)
                except Exception as exc:  # noqa: BLE001 - refused, timed out, DNS: all mean "not now"
                    raise ClusterUnavailable(f"cannot connect to the Dask scheduler {self.scheduler}: "
                                             f"{type(exc).__name__}: {exc}") from None
        if getattr(self._client, "status", "running") not in ("running", "newly-created"):
            raise ClusterUnavailable(f"the Dask client is {self._client.status} (scheduler {self.scheduler} lost)")
        return self._client

    def _drop_client(self) -> None:
        client, self._client = self._client, None
        if client is not None and client is not self.scheduler:
            try:
                client.close(timeout=2)
            except Exception:  # noqa: BLE001 - it is already broken; closing is best effort
                pass

    def _workers(self) -> dict[str, int]:
        """Alive Dask workers and their threads (asks the scheduler)."""
        return dict(self.client.nthreads())

    def _capacity(self, workers: dict[str, int]) -> int:
        if not workers:
            return 0  # nothing can run: claim nothing, so jobs wait in the queue, not in a lost lease
        return self.capacity or sum(workers.values())

    # -- one round --------------------------------------------------------------------------------------

    def _fill(self, workers: dict[str, int]) -> None:
        from distributed import Variable

        while len(self.inflight) < self._capacity(workers) and not self.stop.is_set():
            with self.session_factory() as session:
                job = claim_next(session, self.worker_id, self.settings.lease_s)
            if job is None:
                return
            try:
                progress_name, cancel_name = _names(job.id, job.attempts)
                Variable(progress_name, client=self.client).set([0.0, "submitted"])
                Variable(cancel_name, client=self.client).set(False)
                future = self.client.submit(run_on_dask, job.evaluator, job.spec, job.id, job.attempts,
                                            key=f"demcal-job-{job.id}-{job.attempts}", pure=False)
            except Exception:
                with self.session_factory() as session:  # not dispatched: hand it back uncounted
                    release_job(session, job.id, self.worker_id)
                raise
            self.inflight[job.id] = _InFlight(job.id, job.attempts, future)
            log.info("dispatched job %s (attempt %s) to dask", job.id, job.attempts)

    def _forget(self, entry: _InFlight) -> None:
        from distributed import Variable

        self.inflight.pop(entry.job_id, None)
        if self._client is None:
            return
        for name in _names(entry.job_id, entry.attempt):
            try:
                Variable(name, client=self._client).delete()
            except Exception:  # already gone with the scheduler: nothing to clean
                pass

    def _requeue_all(self, reason: str) -> None:
        """Every job in flight back to the queue, its attempt counted (the executor lost it)."""
        for entry in list(self.inflight.values()):
            try:
                entry.future.cancel()
            except Exception:  # noqa: BLE001 - the client may be gone
                pass
            with self.session_factory() as session:
                if requeue_job(session, entry.job_id, self.worker_id, reason):
                    log.warning("job %s requeued: %s", entry.job_id, reason)
            self._forget(entry)

    def _track_reruns(self, workers: dict[str, int]) -> None:
        """Dask re-runs a task whose worker died, on another worker; that re-run is an attempt too.

        A task is re-run when the worker last seen processing it is gone: either absent from the alive
        workers, or the task shows up elsewhere and a fresh look no longer finds its old worker (the
        alive list may lag the task's move). A move to another live worker is work stealing, not a re-run.
        """
        where = {key: worker for worker, keys in self.client.processing().items() for key in keys}
        fresh: dict[str, int] | None = None
        for entry in list(self.inflight.values()):
            current, previous = where.get(entry.future.key), entry.dask_worker
            died = previous is not None and previous not in workers
            if not died and previous is not None and current is not None and current != previous:
                fresh = self._workers() if fresh is None else fresh
                died = previous not in fresh
            if died and not self._count_rerun(entry, previous):
                continue
            if current is not None or died:
                entry.dask_worker = current

    def _count_rerun(self, entry: _InFlight, dead_worker: str) -> bool:
        """Count the re-run; False (and the job failed) once it exceeds ``max_attempts``."""
        with self.session_factory() as session:
            attempts = count_attempt(session, entry.job_id, self.worker_id)
            if attempts is None:
                return False
            job = session.get(self._job_model(), entry.job_id)
            if attempts > job.max_attempts:
                entry.future.cancel()
                finish_job(session, entry.job_id, self.worker_id, JobStatus.FAILED,
                           f"lost its Dask worker {attempts - 1} times (max_attempts={job.max_attempts})")
                self._forget(entry)
                return False
        log.warning("job %s: Dask worker %s died; Dask re-runs the task (attempt %s)", entry.job_id, dead_worker,
                    attempts)
        return True

    @staticmethod
    def _job_model():
        from service.models.job import Job

        return Job

    def _beat(self) -> None:
        from distributed import Variable

        for entry in list(self.inflight.values()):
            progress_name, cancel_name = _names(entry.job_id, entry.attempt)
            try:
                fraction, phase = Variable(progress_name, client=self.client).get(timeout=5)
            except Exception:
                fraction, phase = None, None
            with self.session_factory() as session:
                try:
                    cancel = heartbeat(session, entry.job_id, self.worker_id, self.settings.lease_s, fraction, phase)
                except LeaseLost:
                    log.warning("lost the lease of job %s; dropping its Dask task", entry.job_id)
                    entry.future.cancel()
                    self._forget(entry)
                    continue
            if cancel and not entry.cancel_requested:
                entry.cancel_requested = True
                Variable(cancel_name, client=self.client).set(True)
                if entry.future.status == "pending":
                    entry.future.cancel()

    def _collect(self) -> None:
        for entry in list(self.inflight.values()):
            future = entry.future
            if future.status == "pending":
                continue
            elapsed = time.perf_counter() - entry.started
            with self.session_factory() as session:
                if future.status == "finished":
                    result = LabResult.model_validate(future.result())
                    if not complete_job(session, entry.job_id, self.worker_id, result, elapsed):
                        log.warning("job %s: lease lost before its result arrived; discarded", entry.job_id)
                elif entry.cancel_requested:
                    finish_job(session, entry.job_id, self.worker_id, JobStatus.CANCELLED, "cancelled while running",
                               elapsed)
                elif future.status == "error":
                    exc = future.exception()
                    tb = "".join(traceback.format_tb(future.traceback())) if future.traceback() else ""
                    reason = public_error(exc)
                    log.warning("job %s failed on dask: %s\n%s", entry.job_id, reason, tb)
                    finish_job(session, entry.job_id, self.worker_id, JobStatus.FAILED, reason, elapsed)
                else:  # cancelled or lost by Dask itself (e.g. scheduler restart): run it again, counted
                    requeue_job(session, entry.job_id, self.worker_id, f"the Dask task ended {future.status}")
            self._forget(entry)

    def round(self, beat: bool) -> None:
        """One dispatcher round: collect results, renew leases (only while a worker is alive), fill."""
        workers = self._workers()
        if workers:
            self._track_reruns(workers)  # before collecting: a fast re-run may already have finished
        self._collect()
        if not workers:
            if self.inflight:
                self._requeue_all("no Dask worker is alive")
            self._set_health(False, "no Dask worker is alive")
            return
        if beat:
            self._beat()
        self._fill(workers)
        self._set_health(True, None)

    def _set_health(self, healthy: bool, problem: str | None) -> None:
        if healthy and not self.healthy:
            log.warning("dask dispatcher: cluster %s usable", self.scheduler)
        self.healthy, self.problem = healthy, problem

    def run(self) -> None:
        last_beat, failures, last_reason = time.monotonic(), 0, None
        try:
            while not self.stop.is_set():
                wait = min(self.settings.poll_interval_s, 0.2)
                try:
                    beat = time.monotonic() - last_beat >= self.settings.heartbeat_s
                    self.round(beat)
                    if beat:
                        last_beat = time.monotonic()
                    failures = 0
                except Exception as exc:  # noqa: BLE001 - any outage: requeue, report, reconnect with back-off
                    failures += 1
                    reason = str(exc) if isinstance(exc, ClusterUnavailable) else f"{type(exc).__name__}: {exc}"
                    reason = reason.splitlines()[0] if reason else type(exc).__name__
                    self._set_health(False, reason)
                    wait = min(MAX_BACKOFF_S, 0.5 * 2 ** min(failures, 8))
                    if reason != last_reason:
                        log.error("dask dispatcher: %s; retrying in %.1f s", reason, wait)
                        last_reason = reason
                    self._requeue_all(f"the Dask scheduler was lost ({reason})")
                    self._drop_client()
                self.stop.wait(wait)
        finally:
            self._shutdown()

    def _shutdown(self) -> None:
        """Hand unfinished jobs back so another executor picks them up without waiting for the lease."""
        for entry in list(self.inflight.values()):
            try:
                entry.future.cancel()
            except Exception:  # noqa: BLE001
                pass
            with self.session_factory() as session:
                release_job(session, entry.job_id, self.worker_id)
            self.inflight.pop(entry.job_id, None)
        self._drop_client()
