"""Schema history: an old database upgrades to head without loss; models match the migrations."""
from __future__ import annotations

import json

import pytest
from alembic.autogenerate import compare_metadata
from alembic.runtime.migration import MigrationContext
from sqlalchemy import text

from engine.lab.spec import JobSpec
from service.db import make_engine
from service.migrate import current_revision, head_revision, upgrade
from service.models import Base

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)


def test_upgrade_from_0001_keeps_jobs(db_url):
    assert upgrade(db_url, "0001_jobs") == "0001_jobs"
    engine = make_engine(db_url)
    specs = [JobSpec(test="dst", seed=i, parameters={"friction_pp": 0.1 * i}).model_dump(mode="json") for i in range(5)]
    rows = [
        {"status": status, "evaluator": "dem", "test": "dst", "fidelity": "screening", "spec": json.dumps(spec),
         "seed": spec["seed"], "priority": i, "attempts": 1 if status != "queued" else 0, "max_attempts": 3,
         "cancel_requested": False, "progress_fraction": 1.0 if status == "succeeded" else 0.0,
         "result": json.dumps({"test": "dst", "value": i}) if status == "succeeded" else None,
         "error": "diverged" if status == "failed" else None, "created_at": "2026-11-01 10:00:00",
         "client_id": "lab-a", "idempotency_key": f"key-{i}", "campaign_id": 7 if i % 2 else None}
        for i, (spec, status) in enumerate(zip(specs, ["queued", "succeeded", "failed", "running", "cancelled"]))
    ]
    with engine.begin() as conn:
        conn.execute(text(
            "INSERT INTO jobs (status, evaluator, test, fidelity, spec, seed, priority, attempts, max_attempts,"
            " cancel_requested, progress_fraction, result, error, created_at, client_id, idempotency_key, campaign_id)"
            " VALUES (:status, :evaluator, :test, :fidelity, :spec, :seed, :priority, :attempts, :max_attempts,"
            " :cancel_requested, :progress_fraction, :result, :error, :created_at, :client_id, :idempotency_key,"
            " :campaign_id)"), rows)
        before = conn.execute(text("SELECT * FROM jobs ORDER BY id")).mappings().all()
    engine.dispose()

    assert upgrade(db_url) == head_revision()
    engine = make_engine(db_url)
    with engine.connect() as conn:
        after = conn.execute(text("SELECT * FROM jobs ORDER BY id")).mappings().all()
    # every stored value kept; the owner columns of 0004 are NULL: nobody's (service.ownership)
    assert [{k: r[k] for k in before[0]} for r in after] == [dict(r) for r in before]
    assert {r["owner"] for r in after} == {None}
    spec = after[1]["spec"]  # SQLite hands JSON columns back as text to raw SQL, PostgreSQL as decoded JSON
    assert (json.loads(spec) if isinstance(spec, str) else spec) == specs[1]
    assert current_revision(engine) == head_revision()
    # Upgrading again is a no-op.
    assert upgrade(db_url) == head_revision()
    engine.dispose()


def test_models_match_migrations(db_url):
    """Schema changes go through Alembic: head must equal what the ORM declares."""
    upgrade(db_url)
    engine = make_engine(db_url)
    with engine.connect() as conn:
        diff = compare_metadata(MigrationContext.configure(conn, opts={"compare_type": True}), Base.metadata)
    engine.dispose()
    assert diff == []


def test_sqlite_pragmas(tmp_path):
    engine = make_engine(f"sqlite:///{(tmp_path / 'demcal.db').as_posix()}")
    with engine.connect() as conn:
        assert conn.execute(text("PRAGMA journal_mode")).scalar() == "wal"
        assert conn.execute(text("PRAGMA foreign_keys")).scalar() == 1
        assert conn.execute(text("PRAGMA busy_timeout")).scalar() >= 1000
    engine.dispose()
