"""Schema upgrades through Alembic, configured in code (no alembic.ini at the repo top).

Called by ``demcal db upgrade`` and at service start, so a fresh machine and an
old database both end at the head revision without a manual step.
"""
from __future__ import annotations

from pathlib import Path

from alembic import command
from alembic.config import Config
from alembic.runtime.migration import MigrationContext
from alembic.script import ScriptDirectory

import migrations
from service.db import make_engine


def alembic_config(database_url: str, connection=None) -> Config:
    config = Config()
    # __path__, not __file__: an editable install may expose migrations/ as a namespace package.
    config.set_main_option("script_location", str(Path(next(iter(migrations.__path__))).resolve()))
    config.set_main_option("sqlalchemy.url", database_url.replace("%", "%%"))
    if connection is not None:
        config.attributes["connection"] = connection
    return config


def upgrade(database_url: str, revision: str = "head") -> str:
    """Upgrade to ``revision``; returns the revision the database is at afterwards."""
    engine = make_engine(database_url)
    try:
        with engine.begin() as conn:
            command.upgrade(alembic_config(database_url, conn), revision)
        return current_revision(engine)
    finally:
        engine.dispose()


def current_revision(engine) -> str | None:
    with engine.connect() as conn:
        return MigrationContext.configure(conn).get_current_revision()


def head_revision(database_url: str = "sqlite://") -> str | None:
    return ScriptDirectory.from_config(alembic_config(database_url)).get_current_head()
