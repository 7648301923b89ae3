"""Worker processes: the standalone entry point and the pool ``demcal serve`` supervises.

Workers are separate processes (not threads) because a DEM job holds a core for
a long time and numba kernels hold the GIL; they share nothing with the API but
the database URL and the ``DEMCAL_*`` settings passed through the environment.
"""
from __future__ import annotations

import logging
import os
import signal
import subprocess
import sys
import threading
import time

from service.config import Settings, settings_from_env
from service.db import make_engine, make_session_factory

log = logging.getLogger(__name__)


def settings_env(settings: Settings) -> dict[str, str]:
    """The environment a child process needs to rebuild ``settings``."""
    env = dict(os.environ)
    for name, value in settings.model_dump().items():
        key = "DEMCAL_" + name.upper()
        if value is None:
            env.pop(key, None)
        else:
            env[key] = str(value)
    return env


def _watch_parent(stop) -> None:
    """A pool worker stops when the ``demcal serve`` that started it is gone (even after kill -9)."""
    parent = os.environ.get("DEMCAL_PARENT_PID")
    if not parent:
        return

    def watch() -> None:
        while not stop.wait(1.0):
            if os.getppid() != int(parent):
                log.warning("parent %s is gone; stopping", parent)
                stop.set()

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def run_worker(settings: Settings) -> int:
    """Run one worker (or a Dask dispatcher) until SIGTERM/SIGINT; the current job is handed back."""
    engine = make_engine(settings.database_url)
    session_factory = make_session_factory(engine, settings)
    if settings.dask_scheduler:
        from service.workers.dask_executor import DaskDispatcher

        runner = DaskDispatcher(session_factory, settings, settings.dask_scheduler)
    else:
        from service.workers.local import Worker

        runner = Worker(session_factory, settings)

    def _stop(_signum, _frame):
        runner.stop.set()

    signal.signal(signal.SIGTERM, _stop)
    signal.signal(signal.SIGINT, _stop)
    _watch_parent(runner.stop)
    log.info("worker %s polling %s", getattr(runner, "worker_id", "?"), settings.database_url)
    try:
        runner.run()
    finally:
        engine.dispose()
    return 0


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(prog="python -m service.workers", description="run one demcal worker")
    parser.add_argument("--db", help="SQLAlchemy URL (default: DEMCAL_DATABASE_URL or ./demcal-data/demcal.db)")
    parser.add_argument("--dask-scheduler", help="dispatch to this Dask scheduler instead of running locally")
    args = parser.parse_args(argv)
    logging.basicConfig(level=os.environ.get("DEMCAL_LOG_LEVEL", "INFO"),
                        format="%(asctime)s %(process)d %(name)s %(levelname)s %(message)s")
    return run_worker(settings_from_env(database_url=args.db, dask_scheduler=args.dask_scheduler))


def job_threads(settings: Settings, workers: int) -> int:
    """Numba threads per worker: the configured value, else the cores shared out among the workers.

    Why not every core for every job: workers that each start one thread per core oversubscribe the
    machine, and OpenMP's barriers (two or three parallel regions per DEM step) then stall whenever a
    thread is descheduled. And even alone a two-thread job is less than twice as fast as a one-thread
    job, so on two cores two one-thread jobs side by side finish more batteries per hour
    (bench/battery_threads.py measures it; docs/engine.md has the figures).
    """
    if settings.threads_per_job is not None:
        return settings.threads_per_job
    return max(1, (os.cpu_count() or 1) // max(1, workers))


class LocalWorkerPool:
    """Starts ``count`` worker processes, restarts any that die, stops them on shutdown."""

    def __init__(self, settings: Settings, count: int):
        self.settings, self.count = settings, count
        self.processes: list[subprocess.Popen] = []
        self.stopping = False

    def _spawn(self) -> subprocess.Popen:
        env = dict(settings_env(self.settings), DEMCAL_PARENT_PID=str(os.getpid()))
        env["NUMBA_NUM_THREADS"] = str(job_threads(self.settings, self.count))
        return subprocess.Popen([sys.executable, "-m", "service.workers"], env=env)

    def start(self) -> None:
        self.processes = [self._spawn() for _ in range(self.count)]

    def supervise(self) -> None:
        if self.stopping:
            return
        for i, proc in enumerate(self.processes):
            if proc.poll() is not None:
                log.warning("worker pid %s exited with %s; starting a new one", proc.pid, proc.returncode)
                self.processes[i] = self._spawn()

    def alive(self) -> int:
        return sum(proc.poll() is None for proc in self.processes)

    def pids(self) -> list[int]:
        return [proc.pid for proc in self.processes if proc.poll() is None]

    def stop(self, timeout_s: float = 10.0) -> None:
        self.stopping = True
        for proc in self.processes:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + timeout_s
        for proc in self.processes:
            try:
                proc.wait(max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        self.processes = []
