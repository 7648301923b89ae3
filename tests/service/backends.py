"""The database backends the service tests run on: SQLite always, PostgreSQL when a server is given.

Why both: SQLite is the default store, but a team running workers on several machines needs a server
database, and PostgreSQL runs concurrent writers on snapshots under row locks where SQLite serialises them
behind one file lock, so the queue's conditional updates, the per-client limit and the idempotency index
behave differently there. A test module opts in with ``pytestmark = pytest.mark.postgres``; each of its tests
that uses a database then runs once per backend (ids ``[sqlite]`` and ``[postgresql]``).

The PostgreSQL server is named by ``DEMCAL_TEST_POSTGRES_URL`` (any database on it; a superuser or a role
that may create databases), e.g. ``postgresql+psycopg://postgres@/postgres?host=/tmp/demcal-pg`` as printed
by ``.ci/postgres start /tmp/demcal-pg``. Each test gets a database of its own, created empty and dropped
afterwards. Without the variable the PostgreSQL cases are skipped, saying why; with
``DEMCAL_REQUIRE_POSTGRES=1`` (set by ``.ci/run``) they fail instead, so CI cannot pass without them.
"""
from __future__ import annotations

import itertools
import os

import pytest
from sqlalchemy import create_engine
from sqlalchemy.engine import make_url
from sqlalchemy.pool import NullPool

SQLITE = "sqlite"
POSTGRESQL = "postgresql"
BACKENDS = (SQLITE, POSTGRESQL)
URL_ENV = "DEMCAL_TEST_POSTGRES_URL"
REQUIRE_ENV = "DEMCAL_REQUIRE_POSTGRES"

_names = itertools.count()


def unavailable(reason: str) -> None:
    """Skip the PostgreSQL case locally; fail it in CI, where the server must be there."""
    if os.environ.get(REQUIRE_ENV, "") not in ("", "0"):
        pytest.fail(f"{REQUIRE_ENV} is set but {reason}", pytrace=False)
    pytest.skip(f"PostgreSQL case skipped: {reason} (start one with .ci/postgres start DIR and set {URL_ENV})")


def server_url() -> str:
    """The administrative URL of the test server, or a skip/fail saying what is missing."""
    url = os.environ.get(URL_ENV, "").strip()
    if not url:
        unavailable(f"{URL_ENV} is not set")
    try:
        import psycopg  # noqa: F401  (the driver the URL names: postgresql+psycopg://)
    except ImportError:
        unavailable("the psycopg driver is not installed (pip install -e '.[test]')")
    return url


def _admin_engine(url: str):
    # CREATE/DROP DATABASE cannot run inside a transaction; no pool: nothing may stay connected
    return create_engine(url, isolation_level="AUTOCOMMIT", poolclass=NullPool)


def create_database(url: str, label: str) -> str:
    """A new empty database on the server of ``url``; returns its URL (same credentials and host)."""
    name = f"demcal_t{os.getpid()}_{next(_names)}_{''.join(c for c in label.lower() if c.isalnum())[:30]}"
    engine = _admin_engine(url)
    try:
        with engine.connect() as conn:
            conn.exec_driver_sql(f'DROP DATABASE IF EXISTS "{name}"')
            conn.exec_driver_sql(f'CREATE DATABASE "{name}" TEMPLATE template0 ENCODING \'UTF8\'')
    except Exception as exc:  # noqa: BLE001  (any driver error: the server is not usable)
        unavailable(f"cannot create a database on {URL_ENV}: {str(exc).splitlines()[0]}")
    finally:
        engine.dispose()
    return make_url(url).set(database=name).render_as_string(hide_password=False)


def drop_database(url: str, database_url: str) -> None:
    """Drop a test database, closing what a killed server or worker left connected (PostgreSQL 13+)."""
    name = make_url(database_url).database
    engine = _admin_engine(url)
    try:
        with engine.connect() as conn:
            conn.exec_driver_sql(f'DROP DATABASE IF EXISTS "{name}" WITH (FORCE)')
    finally:
        engine.dispose()
