"""Storage preflight and one-line storage errors.

Why: ``demcal serve`` on a read-only database or an uncreatable directory used to print 18-142
lines of traceback; an operator needs one line saying which file and why, and a non-zero exit.
``check_storage`` runs before anything listens or claims jobs: it creates the directory, brings
the schema to head and proves a write is possible (an update that changes nothing, rolled back).
"""
from __future__ import annotations

from sqlalchemy.engine import make_url
from sqlalchemy.exc import DBAPIError, SQLAlchemyError


class StorageError(Exception):
    """A storage failure, its message one line fit for stderr or a log."""


def describe(exc: BaseException) -> str:
    """One line for any storage exception: the driver's own message, without SQL or traceback."""
    if isinstance(exc, DBAPIError) and exc.orig is not None:
        return f"{type(exc.orig).__name__}: {exc.orig}".splitlines()[0]
    if isinstance(exc, OSError):
        where = f" {exc.filename}" if exc.filename else ""
        return f"{type(exc).__name__}:{where}: {exc.strerror or exc}"
    text = str(exc).splitlines()[0] if str(exc) else ""
    return f"{type(exc).__name__}: {text}" if text else type(exc).__name__


def _where(database_url: str) -> str:
    try:
        url = make_url(database_url)
    except SQLAlchemyError:
        return database_url
    return url.database if url.get_backend_name() == "sqlite" and url.database else url.render_as_string(
        hide_password=True)


def check_storage(database_url: str) -> str:
    """Create, upgrade and write-probe the database; returns its schema revision or raises StorageError."""
    from service.db import make_engine
    from service.migrate import upgrade

    where = _where(database_url)
    try:
        revision = upgrade(database_url)
        engine = make_engine(database_url)
        try:
            with engine.connect() as conn:  # a write that changes nothing, rolled back
                with conn.begin() as tx:
                    conn.exec_driver_sql("UPDATE alembic_version SET version_num = version_num")
                    tx.rollback()
        finally:
            engine.dispose()
    except Exception as exc:  # noqa: BLE001 - every failure becomes the one line below
        raise StorageError(f"database {where} is not usable: {describe(exc)}") from exc
    return revision or ""
