"""The queue's claim/lease semantics on PostgreSQL (runs where ``postgres`` and psycopg exist).

SQLite serialises writers with a file lock; PostgreSQL runs them concurrently under
row locks, so the conditional UPDATEs are checked there too, against a throwaway
cluster started for this module.
"""
from __future__ import annotations

import os
import shutil
import socket
import subprocess
import tempfile
import threading
import time

import pytest

from engine.lab.spec import JobSpec
from service import queue
from service.config import Settings
from service.db import make_engine, make_session_factory
from service.migrate import head_revision, upgrade

pytest.importorskip("psycopg")
if shutil.which("initdb") is None or shutil.which("pg_ctl") is None:
    pytest.skip("PostgreSQL server binaries not installed", allow_module_level=True)


def _as_postgres_user(cmd: list[str]) -> list[str]:
    """initdb refuses to run as root; drop to the 'postgres' account when we are root."""
    if os.geteuid() == 0:
        return ["runuser", "-u", "postgres", "--", *cmd]
    return cmd


@pytest.fixture(scope="module")
def pg_url():
    root = tempfile.mkdtemp(prefix="demcal-pg-")
    os.chmod(root, 0o755)
    data = os.path.join(root, "data")
    if os.geteuid() == 0:
        shutil.chown(root, "postgres")
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    run = lambda *cmd: subprocess.run(_as_postgres_user(list(cmd)), check=True, capture_output=True,  # noqa: E731
                                      timeout=120)
    run("initdb", "-D", data, "--auth=trust", "-U", "postgres")
    run("pg_ctl", "-D", data, "-w", "-l", os.path.join(root, "log"),
        "-o", f"-p {port} -k {root} -c listen_addresses=127.0.0.1 -c fsync=off", "start")
    try:
        yield f"postgresql+psycopg://postgres@127.0.0.1:{port}/postgres"
    finally:
        subprocess.run(_as_postgres_user(["pg_ctl", "-D", data, "-m", "immediate", "stop"]), capture_output=True,
                       timeout=60)
        shutil.rmtree(root, ignore_errors=True)


@pytest.fixture
def pg_sessions(pg_url):
    assert upgrade(pg_url) == head_revision()
    engine = make_engine(pg_url)
    with engine.begin() as conn:
        conn.exec_driver_sql("TRUNCATE jobs RESTART IDENTITY")
    yield make_session_factory(engine, Settings(database_url=pg_url))
    engine.dispose()


def test_concurrent_claims_on_postgres(pg_sessions):
    with pg_sessions() as s:
        ids = {queue.submit_job(s, JobSpec(seed=i), evaluator="analytic").id for i in range(60)}
    claimed: list[int] = []
    lock = threading.Lock()

    def claimer(name: str) -> None:
        with pg_sessions() as s:
            while (job := queue.claim_next(s, name, 30)) is not None:
                with lock:
                    claimed.append(job.id)

    threads = [threading.Thread(target=claimer, args=(f"w{i}",)) for i in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert sorted(claimed) == sorted(ids)


def test_lease_expiry_idempotency_and_late_ack_on_postgres(pg_sessions):
    results: list[int] = []

    def submit() -> None:
        with pg_sessions() as s:
            results.append(queue.submit_job(s, JobSpec(seed=3), evaluator="analytic", idempotency_key="k").id)

    threads = [threading.Thread(target=submit) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(set(results)) == 1
    job_id = results[0]
    with pg_sessions() as s:
        assert queue.claim_next(s, "dead", 0.05).id == job_id
        time.sleep(0.1)
        assert queue.claim_next(s, "alive", 30).id == job_id
        with pytest.raises(queue.LeaseLost):
            queue.heartbeat(s, job_id, "dead", 30)
        assert queue.heartbeat(s, job_id, "alive", 30, 0.5, "shearing") is False
        from calibration.evaluator_registry import run_job

        assert queue.complete_job(s, job_id, "alive", run_job("analytic", JobSpec(seed=3)), 0.1)
        job = queue.get_job(s, job_id)
    assert job.status == "succeeded" and job.attempts == 2 and job.result["provenance"]["seed"] == 3
