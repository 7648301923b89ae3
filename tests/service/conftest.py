"""Fixtures for the service tests: a fresh database per test, in-process app, real servers."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from service.app import create_app
from service.config import Settings
from service.db import make_engine, make_session_factory
from service.migrate import upgrade


from service_net import LOCAL_BASE_URL, LOOPBACK_PEER, free_port, wait_healthy  # noqa: F401  (re-exported for older imports)

import backends


def pytest_generate_tests(metafunc):
    """Every test of a module marked ``postgres`` that uses a database runs once per backend."""
    if "db_backend" in metafunc.fixturenames and metafunc.definition.get_closest_marker("postgres"):
        metafunc.parametrize("db_backend", backends.BACKENDS, indirect=True)


@pytest.fixture
def db_backend(request) -> str:
    return getattr(request, "param", backends.SQLITE)


@pytest.fixture
def db_url(db_backend: str, tmp_path: Path, request):
    """A fresh, empty database for the test: a SQLite file, or a database of its own on the PostgreSQL server."""
    if db_backend == backends.SQLITE:
        yield f"sqlite:///{(tmp_path / 'demcal.db').as_posix()}"
        return
    server = backends.server_url()
    url = backends.create_database(server, request.node.name)
    yield url
    backends.drop_database(server, url)


@pytest.fixture
def settings(db_url: str) -> Settings:
    """No executors or ticks: tests drive workers themselves, deterministically."""
    return Settings(database_url=db_url, start_workers=False, start_background=False, seed_materials=False,
                    lease_s=2.0, heartbeat_s=0.2, poll_interval_s=0.05)


@pytest.fixture
def session_factory(settings: Settings):
    upgrade(settings.database_url)
    engine = make_engine(settings.database_url)
    yield make_session_factory(engine, settings)
    engine.dispose()


@pytest.fixture
def client(settings: Settings):
    with TestClient(create_app(settings), base_url=LOCAL_BASE_URL, client=LOOPBACK_PEER) as test_client:
        yield test_client


def service_env(db_url: str, **extra: str) -> dict[str, str]:
    env = dict(os.environ)
    env.update({"DEMCAL_DATABASE_URL": db_url, "DEMCAL_SEED_MATERIALS": "false", "DEMCAL_LOG_LEVEL": "WARNING",
                "PYTHONUNBUFFERED": "1"})
    env.update(extra)
    return env


def demcal_cmd(*args: str) -> list[str]:
    """``demcal ...`` through the interpreter running the tests (no PATH assumptions)."""
    return [sys.executable, "-m", "service.cli", *args]




def stop_process(proc: subprocess.Popen, timeout_s: float = 15.0) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@pytest.fixture(name="service_env")
def service_env_fixture():
    return service_env


@pytest.fixture(name="demcal_cmd")
def demcal_cmd_fixture():
    return demcal_cmd


@pytest.fixture
def live_server(db_url: str):
    """``demcal serve`` as a real process (uvicorn on loopback); yields (base_url, env, proc)."""
    servers: list[subprocess.Popen] = []

    def start(workers: int = 0, **env_extra: str):
        port = free_port()
        env = service_env(db_url, **env_extra)
        proc = subprocess.Popen(demcal_cmd("serve", "--port", str(port), "--workers", str(workers)), env=env)
        servers.append(proc)
        base_url = f"http://127.0.0.1:{port}"
        wait_healthy(base_url, proc)
        return base_url, env, proc

    yield start
    for proc in servers:
        stop_process(proc)
