"""Revision 0002_campaigns and the later ones: they apply on a database at 0001_jobs without touching its jobs,
and revert to it (on SQLite and on PostgreSQL)."""
from __future__ import annotations

import pytest
import sqlalchemy as sa
from alembic import command
from alembic.autogenerate import compare_metadata
from alembic.migration import MigrationContext

from service.db import make_engine
from service.migrate import alembic_config, head_revision, upgrade
from service.models import Base

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)

S2_TABLES = {"materials", "measurements", "campaigns", "campaign_iterations", "campaign_runs", "schedules",
             "schedule_firings"}


def test_later_revisions_upgrade_a_populated_0001_database_and_downgrade(db_url):
    url = db_url
    assert upgrade(url, "0001_jobs") == "0001_jobs"
    engine = make_engine(url)
    with engine.begin() as conn:
        conn.execute(sa.text(
            "INSERT INTO jobs (status, evaluator, test, fidelity, spec, seed, priority, attempts, max_attempts, "
            "cancel_requested, progress_fraction, created_at, client_id) VALUES ('succeeded', 'analytic', "
            "'battery', 'screening', '{}', 7, 0, 1, 3, FALSE, 1.0, '2026-11-22 00:00:00', 'old-client')"))
    assert upgrade(url) == head_revision()
    tables = set(sa.inspect(engine).get_table_names())
    assert S2_TABLES <= tables
    with engine.connect() as conn:
        assert conn.execute(sa.text("SELECT seed, client_id FROM jobs")).all() == [(7, "old-client")]
        # the migrated schema is exactly what the ORM models declare
        assert compare_metadata(MigrationContext.configure(conn, opts={"compare_type": True}), Base.metadata) == []
    with engine.begin() as conn:
        command.downgrade(alembic_config(url, conn), "0001_jobs")  # the later revisions' downgrades too
    assert not S2_TABLES & set(sa.inspect(engine).get_table_names())
    with engine.connect() as conn:
        assert conn.execute(sa.text("SELECT count(*) FROM jobs")).scalar() == 1
    engine.dispose()
