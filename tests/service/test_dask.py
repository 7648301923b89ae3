"""The Dask executor against a distributed.LocalCluster: results, progress, cancellation, lease."""
from __future__ import annotations

import threading
import time

import pytest
from fastapi.testclient import TestClient
from service_net import LOCAL_BASE_URL

from engine.lab.spec import JobSpec
from service import queue
from service.app import create_app
from service.workers.dask_executor import DaskDispatcher

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def cluster():
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  dashboard_address=None) as local:
        yield local


def _wait(predicate, timeout_s=30.0):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError("timed out")


def test_serve_with_dask_scheduler_runs_jobs(settings, cluster):
    dask_settings = settings.model_copy(update={"dask_scheduler": cluster.scheduler_address, "start_workers": True})
    with TestClient(create_app(dask_settings), base_url=LOCAL_BASE_URL) as client:
        assert client.get("/api/v1/health").json()["executor"] == "dask"
        ids = [client.post("/api/v1/jobs", json={"evaluator": "analytic", "seed": s}).json()["id"] for s in range(3)]
        for job_id in ids:
            job = _wait(lambda: (j := client.get(f"/api/v1/jobs/{job_id}").json())["status"] == "succeeded" and j)
            assert job["lease_owner"].startswith("dask:") and job["attempts"] == 1
        record = client.get(f"/api/v1/jobs/{ids[2]}/result").json()
        assert record["provenance"]["seed"] == 2


def test_dask_progress_cancellation_and_failure(session_factory, settings, cluster, monkeypatch):
    monkeypatch.setenv("DEMCAL_ANALYTIC_DURATION_S", "20")  # the in-process Dask worker sees it
    import calibration.evaluator_registry as evaluators

    real_run_job = evaluators.run_job

    def run_job(evaluator, spec, progress=None, should_cancel=None):
        if spec.seed == 2:
            raise RuntimeError("wall servo lost contact")
        return real_run_job(evaluator, spec, progress, should_cancel)

    monkeypatch.setattr(evaluators, "run_job", run_job)
    with session_factory() as s:
        slow = queue.submit_job(s, JobSpec(seed=1), evaluator="analytic").id
        bad = queue.submit_job(s, JobSpec(seed=2), evaluator="analytic").id
    dispatcher = DaskDispatcher(session_factory, settings, cluster.scheduler_address, capacity=2)
    thread = threading.Thread(target=dispatcher.run, daemon=True)
    thread.start()
    try:
        def job(job_id):
            with session_factory() as s:
                return queue.get_job(s, job_id)

        failed = _wait(lambda: job(bad).status == "failed" and job(bad))
        assert "wall servo lost contact" in failed.error
        _wait(lambda: job(slow).progress_fraction > 0 and job(slow).progress_phase == "analytic")
        with session_factory() as s:
            assert queue.cancel_job(s, slow).cancel_requested
        done = _wait(lambda: job(slow).status == "cancelled" and job(slow), 30)
        assert done.finished_at is not None
    finally:
        dispatcher.stop.set()
        thread.join(30)
