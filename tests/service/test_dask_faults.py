"""Issue 13, Dask faults against a real scheduler and real workers (separate processes, killed for real):
a scheduler outage longer than the client's reconnect window, and every Dask worker gone mid-job."""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time

import pytest
from service_net import LOCAL_BASE_URL, LOOPBACK_PEER, free_port
from fastapi.testclient import TestClient

from service.app import create_app

distributed = pytest.importorskip("distributed")
pytestmark = pytest.mark.slow  # real processes started and killed: ~1 min

API = "/api/v1"
CONNECT_TIMEOUT_S = 2.0  # the dispatcher's Dask client gives up reconnecting after this


def _listening(port: int) -> bool:
    with socket.socket() as sock:
        sock.settimeout(0.5)
        return sock.connect_ex(("127.0.0.1", port)) == 0


def _wait(predicate, timeout_s: float, what: str):
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out waiting for {what}")


class Cluster:
    """A ``dask scheduler`` and ``dask worker`` processes on a fixed loopback port, restartable."""

    def __init__(self):
        self.port = free_port()
        self.address = f"tcp://127.0.0.1:{self.port}"
        self.scheduler: subprocess.Popen | None = None
        self.workers: list[subprocess.Popen] = []

    def start_scheduler(self) -> None:
        self.scheduler = subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_scheduler", "--host", "127.0.0.1", "--port",
             str(self.port), "--no-dashboard"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        _wait(lambda: _listening(self.port), 60, "the scheduler")

    def start_worker(self, **env: str) -> subprocess.Popen:
        proc = subprocess.Popen(
            [sys.executable, "-m", "distributed.cli.dask_worker", self.address, "--nthreads", "1", "--no-nanny",
             "--no-dashboard", "--death-timeout", "120"],
            env={**os.environ, **env}, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        self.workers.append(proc)
        return proc

    @staticmethod
    def kill(proc: subprocess.Popen) -> None:
        if proc.poll() is None:
            proc.send_signal(signal.SIGKILL)
            proc.wait(30)

    def close(self) -> None:
        for proc in [*self.workers, self.scheduler]:
            if proc is not None:
                self.kill(proc)


@pytest.fixture
def cluster():
    local = Cluster()
    local.start_scheduler()
    yield local
    local.close()


def _app(settings, cluster: Cluster, **update):
    return create_app(settings.model_copy(update={
        "dask_scheduler": cluster.address, "start_workers": True, "dask_connect_timeout_s": CONNECT_TIMEOUT_S,
        **update}))


def _job(client, job_id: int) -> dict:
    return client.get(f"{API}/jobs/{job_id}").json()


def _submit(client, seed: int) -> int:
    response = client.post(f"{API}/jobs", json={"evaluator": "analytic", "seed": seed})
    assert response.status_code == 201, response.text
    return response.json()["id"]


def test_dispatcher_recovers_after_a_scheduler_outage(settings, cluster):
    cluster.start_worker()
    with TestClient(_app(settings, cluster), base_url=LOCAL_BASE_URL, client=LOOPBACK_PEER) as client:
        _wait(lambda: client.get(f"{API}/health").status_code == 200, 60, "a healthy dispatcher")
        first = _submit(client, 1)
        _wait(lambda: _job(client, first)["status"] == "succeeded", 60, "the first job")

        cluster.kill(cluster.scheduler)
        # wait for the dispatcher to see the outage: a loaded machine may answer 503 for another reason first
        # (CI, session 26: "degraded" with dask still healthy, the scheduler's loss not yet noticed)
        down = _wait(lambda: (r := client.get(f"{API}/health")).status_code == 503 and
                     (r.json().get("dask") or {}).get("healthy") is False and r.json(), 30, "dask unhealthy")
        assert down["status"] == "degraded" and down["dask"]["problem"]
        queued = [_submit(client, seed) for seed in (2, 3)]
        time.sleep(3 * CONNECT_TIMEOUT_S)  # longer than the client's reconnect window
        during = client.get(f"{API}/health")
        assert during.status_code == 503 and during.json()["dask"]["healthy"] is False
        assert {_job(client, j)["status"] for j in queued} == {"queued"}  # waiting, neither lost nor failed

        cluster.start_scheduler()
        cluster.start_worker()
        for job_id in queued:
            done = _wait(lambda: (j := _job(client, job_id))["status"] in ("succeeded", "failed") and j, 120,
                         f"job {job_id} after the outage")
            assert done["status"] == "succeeded", done["error"]
        assert client.get(f"{API}/health").status_code == 200


def test_job_whose_dask_workers_are_gone_is_requeued_and_finishes_later(settings, cluster):
    worker = cluster.start_worker(DEMCAL_ANALYTIC_DURATION_S="60")  # long enough to die mid-job
    lease_s = 30.0
    with TestClient(_app(settings, cluster, lease_s=lease_s), base_url=LOCAL_BASE_URL, client=LOOPBACK_PEER) as client:
        _wait(lambda: client.get(f"{API}/health").status_code == 200, 60, "a healthy dispatcher")
        job_id = _submit(client, 7)
        _wait(lambda: (j := _job(client, job_id))["status"] == "running" and j["progress"]["phase"] == "analytic",
              60, "the job running on the Dask worker")
        cluster.kill(worker)
        killed = time.monotonic()
        requeued = _wait(lambda: (j := _job(client, job_id))["status"] == "queued" and j, lease_s, "requeue")
        assert time.monotonic() - killed < lease_s  # within the lease, not after it ran out
        assert requeued["attempts"] == 1 and "no Dask worker" in requeued["error"]
        assert client.get(f"{API}/health").status_code == 503  # nothing can run jobs now

        cluster.start_worker()  # a fast one, started later
        done = _wait(lambda: (j := _job(client, job_id))["status"] in ("succeeded", "failed") and j, 120,
                     "the job on the new worker")
        assert done["status"] == "succeeded", done["error"]
        assert done["attempts"] == 2  # the lost attempt counts


def test_dask_rerun_after_a_worker_death_counts_as_an_attempt(settings, cluster):
    """Dask re-runs the task of a dead worker on another one by itself; the re-run is an attempt."""
    slow = cluster.start_worker(DEMCAL_ANALYTIC_DURATION_S="60")
    with TestClient(_app(settings, cluster), base_url=LOCAL_BASE_URL, client=LOOPBACK_PEER) as client:
        _wait(lambda: client.get(f"{API}/health").status_code == 200, 60, "a healthy dispatcher")
        job_id = _submit(client, 9)
        _wait(lambda: (j := _job(client, job_id))["status"] == "running" and j["progress"]["phase"] == "analytic",
              60, "the job running on the slow worker")
        cluster.start_worker()  # a fast worker joins; the job stays where it is
        with distributed.Client(cluster.address, timeout=30, set_as_default=False) as probe:
            _wait(lambda: len(probe.nthreads()) == 2, 60, "the second worker")
        cluster.kill(slow)
        done = _wait(lambda: (j := _job(client, job_id))["status"] in ("succeeded", "failed") and j, 120,
                     "the re-run on the fast worker")
        assert done["status"] == "succeeded", done["error"]
        assert done["attempts"] == 2
