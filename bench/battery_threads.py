#!/usr/bin/env python3
"""Batteries per hour on this machine: one job with all cores' threads against jobs side by side on one thread.

Why: the service's default numba thread count per worker (service/workers/process.py, job_threads)
must be the one that finishes the most batteries per hour, which is what a calibration costs.

(a) one battery with NUMBA_NUM_THREADS = cores, alone; (b) `cores` batteries at the same time, one
thread each (what `demcal serve` runs with one worker per core). Each battery is a fresh
`demcal run SPEC` process (kernel cache warm: a warm-up run loads or compiles it first).

    python3 bench/battery_threads.py [--spec docs/examples/screening-battery.json]

Last line (machine readable): batteries_per_hour_one_job=X batteries_per_hour_side_by_side=Y best_threads_per_job=Z
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def start(spec: str, threads: int) -> subprocess.Popen:
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads), OMP_NUM_THREADS="1")
    env["PYTHONPATH"] = ROOT + os.pathsep + env.get("PYTHONPATH", "")
    return subprocess.Popen([sys.executable, "-m", "engine.lab.cli", "run", spec], env=env, cwd=ROOT,
                            stdout=subprocess.DEVNULL)


def timed(spec: str, threads: int, jobs: int) -> float:
    """Wall seconds until all `jobs` batteries (started together, `threads` threads each) are done."""
    t = time.perf_counter()
    procs = [start(spec, threads) for _ in range(jobs)]
    for p in procs:
        if p.wait() != 0:
            raise RuntimeError(f"demcal run exited with {p.returncode}")
    return time.perf_counter() - t


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--spec", default=os.path.join("docs", "examples", "screening-battery.json"))
    args = ap.parse_args(argv)
    cores = os.cpu_count() or 1
    print(f"load average before: {os.getloadavg()[0]:.2f} on {cores} cores", flush=True)
    t = timed(args.spec, 1, 1)
    print(f"warm-up battery (1 thread): {t:.0f} s", flush=True)
    one = timed(args.spec, cores, 1)
    print(f"(a) one battery, {cores} threads, alone: {one:.0f} s -> {3600 / one:.1f} batteries/hour", flush=True)
    side = timed(args.spec, 1, cores)
    print(f"(b) {cores} batteries side by side, 1 thread each: {side:.0f} s -> {cores * 3600 / side:.1f} batteries/hour",
          flush=True)
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    best = 1 if cores * 3600 / side >= 3600 / one else cores
    print(f"batteries_per_hour_one_job={3600 / one:.2f} batteries_per_hour_side_by_side={cores * 3600 / side:.2f} "
          f"best_threads_per_job={best}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
