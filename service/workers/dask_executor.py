"""Dask distributed executor: a dispatcher claims jobs and runs them on a Dask cluster.

The dispatcher, not the Dask worker, owns each job's lease: it heartbeats for
every job in flight, so queue semantics are the same as with local workers (a
dead dispatcher's jobs are reclaimed when their leases run out; Dask itself
re-runs a task whose Dask worker died). Dask workers never touch the database:
progress and cancellation cross through two small Dask ``Variable``s per job.
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
from service.queue import LeaseLost, claim_next, complete_job, finish_job, heartbeat, release_job
from service.workers.local import default_worker_id

log = logging.getLogger(__name__)
POLL_REMOTE_S = 1.0  # how often a task asks the scheduler about cancellation / reports progress


def _names(job_id: int, attempt: int) -> tuple[str, str]:
    return f"demcal-progress-{job_id}-{attempt}", f"demcal-cancel-{job_id}-{attempt}"


def run_on_dask(evaluator: str, spec_json: dict, job_id: int, attempt: int) -> dict:
    """The Dask task: evaluate one spec; returns the LabResult as JSON-able data."""
    from distributed import Variable

    from engine.lab.spec import JobSpec
    from service.evaluators import run_spec

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

    return run_spec(evaluator, JobSpec.model_validate(spec_json), progress, should_cancel).model_dump(mode="json")


@dataclass
class _InFlight:
    job_id: int
    attempt: int
    future: object
    started: float = field(default_factory=time.perf_counter)
    cancel_requested: bool = False


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

    @property
    def client(self):
        if self._client is None:
            from distributed import Client

            self._client = self.scheduler if hasattr(self.scheduler, "submit") else Client(self.scheduler)
        return self._client

    def _capacity(self) -> int:
        if self.capacity:
            return self.capacity
        return max(1, sum(self.client.nthreads().values()))

    def _fill(self) -> None:
        from distributed import Variable

        while len(self.inflight) < self._capacity() and not self.stop.is_set():
            with self.session_factory() as session:
                job = claim_next(session, self.worker_id, self.settings.lease_s)
            if job is None:
                return
            progress_name, cancel_name = _names(job.id, job.attempts)
            Variable(progress_name, client=self.client).set([0.0, "submitted"])
            Variable(cancel_name, client=self.client).set(False)
            future = self.client.submit(run_on_dask, job.evaluator, job.spec, job.id, job.attempts,
                                        key=f"demcal-job-{job.id}-{job.attempts}", pure=False)
            self.inflight[job.id] = _InFlight(job.id, job.attempts, future)
            log.info("dispatched job %s (attempt %s) to dask", job.id, job.attempts)

    def _forget(self, entry: _InFlight) -> None:
        from distributed import Variable

        self.inflight.pop(entry.job_id, None)
        for name in _names(entry.job_id, entry.attempt):
            try:
                Variable(name, client=self.client).delete()
            except Exception:  # already gone with the scheduler: nothing to clean
                pass

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
                    finish_job(session, entry.job_id, self.worker_id, "cancelled", "cancelled while running", elapsed)
                elif future.status == "error":
                    exc = future.exception()
                    tb = "".join(traceback.format_tb(future.traceback())) if future.traceback() else ""
                    reason = public_error(exc)
                    log.warning("job %s failed on dask: %s\n%s", entry.job_id, reason, tb)
                    finish_job(session, entry.job_id, self.worker_id, "failed", reason, elapsed)
                else:  # cancelled by Dask itself (e.g. scheduler restart): let another claim run it
                    release_job(session, entry.job_id, self.worker_id)
            self._forget(entry)

    def run(self) -> None:
        last_beat = time.monotonic()
        try:
            while not self.stop.is_set():
                try:
                    self._collect()
                    if time.monotonic() - last_beat >= self.settings.heartbeat_s:
                        self._beat()
                        last_beat = time.monotonic()
                    self._fill()
                except Exception:
                    log.exception("dask dispatcher round failed; retrying")
                self.stop.wait(min(self.settings.poll_interval_s, 0.2))
        finally:
            self._shutdown()

    def _shutdown(self) -> None:
        """Hand unfinished jobs back so another executor picks them up without waiting for the lease."""
        for entry in list(self.inflight.values()):
            entry.future.cancel()
            with self.session_factory() as session:
                release_job(session, entry.job_id, self.worker_id)
            self.inflight.pop(entry.job_id, None)
        if self._client is not None and self._client is not self.scheduler:
            self._client.close()
