"""The demcal command line: db upgrade, argument errors, refusing an unsafe bind."""
from __future__ import annotations

import subprocess

import sys

import pytest

from service.migrate import head_revision


def demcal(*args: str) -> list[str]:
    return [sys.executable, "-m", "service.cli", *args]


def run(*args: str, env=None, timeout=60) -> subprocess.CompletedProcess:
    return subprocess.run(demcal(*args), capture_output=True, text=True, timeout=timeout, env=env)


@pytest.fixture
def env_for(service_env):
    return service_env


def test_db_upgrade_creates_database_at_head(tmp_path):
    db_file = tmp_path / "sub" / "x.db"
    done = run("db", "upgrade", "--db", str(db_file))
    assert done.returncode == 0, done.stderr
    assert f"is at revision {head_revision()}" in done.stdout
    assert db_file.exists()
    again = run("db", "upgrade", "--db", f"sqlite:///{db_file}")
    assert again.returncode == 0 and head_revision() in again.stdout


def test_db_upgrade_reads_env_url(tmp_path, env_for):
    url = f"sqlite:///{tmp_path / 'env.db'}"
    done = run("db", "upgrade", env=env_for(url))
    assert done.returncode == 0 and url in done.stdout


def test_bad_arguments_exit_2_with_message():
    for args, needle in [(("serve", "--port", "abc"), "invalid int value"),
                         (("bogus",), "invalid choice"),
                         (("db",), "required"),
                         (("serve", "--unknown"), "unrecognized arguments")]:
        done = run(*args)
        assert done.returncode == 2, args
        assert needle in done.stderr and "Traceback" not in done.stderr


def test_invalid_setting_and_unsafe_bind_are_refused(tmp_path, env_for):
    url = f"sqlite:///{tmp_path / 'x.db'}"
    done = run("serve", "--port", "70000", "--workers", "0", env=env_for(url))
    assert done.returncode != 0 and "port" in done.stderr and "Traceback" not in done.stderr
    done = run("serve", "--host", "0.0.0.0", "--workers", "0", env=env_for(url))
    assert done.returncode != 0 and "DEMCAL_TOKEN" in done.stderr and "Traceback" not in done.stderr
    done = run("db", "upgrade", "--revision", "nope", "--db", url)
    assert done.returncode == 1 and "nope" in done.stderr and "Traceback" not in done.stderr
