"""500 submissions from 50 concurrent clients against a real uvicorn server: 500 jobs, no more, no less."""
from __future__ import annotations

import threading

import httpx
import pytest
from sqlalchemy import func, select

from service.db import make_engine
from service.models.job import Job

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)

CLIENTS = 50
PER_CLIENT = 10


def test_500_submissions_from_50_clients(live_server, db_url):
    base, _env, _server = live_server(workers=0, DEMCAL_TRUSTED_PROXIES="127.0.0.1")  # X-Client-Id names 50 clients
    created: dict[int, int] = {}  # seed -> job id
    replays: dict[int, int] = {}
    errors: list[str] = []
    lock = threading.Lock()
    barrier = threading.Barrier(CLIENTS)

    def client(index: int) -> None:
        with httpx.Client(base_url=f"{base}/api/v1", timeout=60, headers={"X-Client-Id": f"c{index}"}) as http:
            barrier.wait()
            for k in range(PER_CLIENT):
                seed = index * PER_CLIENT + k
                body = {"evaluator": "analytic", "seed": seed, "idempotency_key": f"s{seed}"}
                r = http.post("/jobs", json=body)
                with lock:
                    if r.status_code != 201:
                        errors.append(f"{seed}: {r.status_code} {r.text}")
                    else:
                        created[seed] = r.json()["id"]
            # A client retrying after a lost response must not create a second job.
            seed = index * PER_CLIENT
            r = http.post("/jobs", json={"evaluator": "analytic", "seed": seed, "idempotency_key": f"s{seed}"})
            with lock:
                if r.status_code != 200:
                    errors.append(f"replay {seed}: {r.status_code} {r.text}")
                else:
                    replays[seed] = r.json()["id"]

    threads = [threading.Thread(target=client, args=(i,)) for i in range(CLIENTS)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(120)
    assert errors == []
    total = CLIENTS * PER_CLIENT
    assert len(created) == total and len(set(created.values())) == total
    assert all(created[seed] == job_id for seed, job_id in replays.items()) and len(replays) == CLIENTS

    engine = make_engine(db_url)
    with engine.connect() as conn:
        assert conn.execute(select(func.count(Job.id))).scalar() == total
        seeds = sorted(conn.execute(select(Job.seed)).scalars())
    engine.dispose()
    assert seeds == list(range(total))  # each submission stored exactly once
    assert httpx.get(f"{base}/api/v1/jobs?limit=1").json()["total"] == total
