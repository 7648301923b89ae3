"""Engine and session plumbing: one storage URL, SQLite by default, any SQLAlchemy URL.

SQLite is tuned for many processes sharing one file (the API, local workers, the
background thread): WAL so readers never block the writer, a busy timeout so a
second writer waits instead of failing, and foreign keys on (off by default there).
PostgreSQL (``postgresql+psycopg://``, tested in CI) gets the JSON codec that keeps
NaN and infinities (``service.json_columns``), which its ``json`` type refuses.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Annotated, Any

from fastapi import Depends, Request
from sqlalchemy import Engine, create_engine, event
from sqlalchemy.engine import make_url
from sqlalchemy.orm import Session, sessionmaker
from sqlalchemy.pool import StaticPool

from service import json_columns

SQLITE_BUSY_TIMEOUT_MS = 30_000


def _is_memory(url) -> bool:
    return url.database in (None, "", ":memory:") or "mode=memory" in str(url)


def _is_uri(url) -> bool:
    return str(url.query.get("uri", "")).lower() == "true" or (url.database or "").startswith("file:")


def make_engine(url: str) -> Engine:
    parsed = make_url(url)
    if parsed.get_backend_name() == "postgresql":
        return create_engine(url, pool_pre_ping=True, json_serializer=json_columns.dumps,
                             json_deserializer=json_columns.loads)
    if parsed.get_backend_name() != "sqlite":
        return create_engine(url, pool_pre_ping=True)
    kwargs: dict = {"connect_args": {"check_same_thread": False, "timeout": SQLITE_BUSY_TIMEOUT_MS / 1000}}
    if _is_memory(parsed):
        kwargs["poolclass"] = StaticPool  # one shared connection, or each would see its own database
    elif not _is_uri(parsed):  # a file: URI (e.g. ?mode=ro) names an existing file; create nothing
        Path(parsed.database).expanduser().parent.mkdir(parents=True, exist_ok=True)
    engine = create_engine(url, **kwargs)

    @event.listens_for(engine, "connect")
    def _sqlite_pragmas(dbapi_conn, _record):
        cursor = dbapi_conn.cursor()
        if not _is_memory(parsed):
            cursor.execute("PRAGMA journal_mode=WAL")
            cursor.execute("PRAGMA synchronous=NORMAL")  # durable at WAL checkpoints, safe against app crashes
        cursor.execute("PRAGMA foreign_keys=ON")
        cursor.execute(f"PRAGMA busy_timeout={SQLITE_BUSY_TIMEOUT_MS}")
        cursor.close()

    return engine


def make_session_factory(engine: Engine, settings=None) -> sessionmaker[Session]:
    """Sessions carry the settings in ``session.info`` so queue code finds the limits."""
    info = {"settings": settings} if settings is not None else {}
    return sessionmaker(bind=engine, expire_on_commit=False, info=info)


def get_session(request: Request) -> Iterator[Session]:
    """FastAPI dependency: one session per request, closed afterwards."""
    session = request.app.state.session_factory()
    try:
        yield session
    finally:
        session.close()


def built_then_committed(session: Session, build: Callable[[], Any], model: Any) -> dict:
    """The response of a write, validated by its response ``model`` and serialised, then the commit.

    Why this order: a write committed before its response was built left a row behind a 500 (a material
    nested past the serialiser's recursion guard was stored, answered 500, and then broke every listing).
    Built after a flush (ids and defaults exist) and before the commit, a failure rolls the write back
    when the request's session closes."""
    session.flush()
    body = model.model_validate(build()).model_dump(mode="json", exclude_unset=True)
    session.commit()
    return body


DbSession = Annotated[Session, Depends(get_session)]
"""The one way a route gets its database session: ``session: DbSession``."""
