"""Submission and read latency (p50, p99) and throughput of the jobs API on loopback.

Starts ``demcal serve --workers 0`` on a fresh SQLite file (or uses --url), then
50 concurrent clients (threads, one httpx.Client each, keep-alive) submit jobs
and read them back. No workers run, so only the API and the database are timed.

    python bench/service.py [--clients 50] [--requests 2000] [--url http://127.0.0.1:8000]
"""
from __future__ import annotations

import argparse
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import httpx
import numpy as np


def _free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def start_server(data_dir: Path) -> tuple[str, subprocess.Popen]:
    port = _free_port()
    env = dict(os.environ, DEMCAL_DATABASE_URL=f"sqlite:///{data_dir / 'bench.db'}", DEMCAL_LOG_LEVEL="WARNING",
               DEMCAL_START_BACKGROUND="false", DEMCAL_MAX_QUEUED_JOBS_PER_CLIENT="1000000")
    proc = subprocess.Popen([sys.executable, "-m", "service.cli", "serve", "--workers", "0", "--port", str(port)],
                            env=env)
    base = f"http://127.0.0.1:{port}"
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            if httpx.get(f"{base}/api/v1/health", timeout=1).status_code == 200:
                return base, proc
        except httpx.HTTPError:
            time.sleep(0.1)
    proc.kill()
    raise SystemExit("server did not start")


def run_phase(base: str, clients: int, total: int, make_request) -> tuple[np.ndarray, float, list]:
    """Each client sends total/clients requests; returns latencies (s), wall time, outputs."""
    per_client = total // clients
    latencies: list[float] = []
    outputs: list = []
    lock = threading.Lock()
    barrier = threading.Barrier(clients + 1)

    def worker(index: int) -> None:
        local_lat, local_out = [], []
        with httpx.Client(base_url=f"{base}/api/v1", timeout=60, headers={"X-Client-Id": f"bench{index}"}) as http:
            barrier.wait()
            for k in range(per_client):
                t0 = time.perf_counter()
                response = make_request(http, index * per_client + k)
                local_lat.append(time.perf_counter() - t0)
                if response.status_code >= 300:
                    raise SystemExit(f"request failed: {response.status_code} {response.text[:200]}")
                local_out.append(response.json().get("id"))
        with lock:
            latencies.extend(local_lat)
            outputs.extend(local_out)

    threads = [threading.Thread(target=worker, args=(i,)) for i in range(clients)]
    for t in threads:
        t.start()
    barrier.wait()
    t0 = time.perf_counter()
    for t in threads:
        t.join()
    return np.asarray(latencies), time.perf_counter() - t0, outputs


def report(name: str, latencies: np.ndarray, wall_s: float) -> None:
    p50, p99 = np.percentile(latencies, [50, 99]) * 1e3
    print(f"{name:<8} n={latencies.size:<6} p50={p50:7.2f} ms  p99={p99:7.2f} ms  "
          f"throughput={latencies.size / wall_s:8.1f} req/s")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--clients", type=int, default=50)
    parser.add_argument("--requests", type=int, default=2000, help="per phase, over all clients")
    parser.add_argument("--url", help="benchmark a running server instead of starting one")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        base, proc = (args.url, None) if args.url else start_server(Path(tmp))
        try:
            run_id = time.time_ns()
            submit_lat, submit_wall, ids = run_phase(base, args.clients, args.requests, lambda http, i: http.post(
                "/jobs", json={"evaluator": "analytic", "seed": i, "idempotency_key": f"bench-{run_id}-{i}"}))
            read_lat, read_wall, _ = run_phase(base, args.clients, args.requests,
                                               lambda http, i: http.get(f"/jobs/{ids[i % len(ids)]}"))
        finally:
            if proc is not None:
                proc.send_signal(signal.SIGTERM)
                proc.wait(30)
    print(f"demcal jobs API on loopback, {args.clients} concurrent clients, SQLite (WAL), no workers")
    report("submit", submit_lat, submit_wall)
    report("read", read_lat, read_wall)
    return 0


if __name__ == "__main__":
    sys.exit(main())
