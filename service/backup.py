"""A consistent copy of the embedded database, and putting one back: ``demcal db backup`` / ``db restore``.

Why: every run a team stores (jobs, batteries, campaigns) lives in one SQLite file, and a long campaign
outlives the machine it started on. Copying the file with ``cp`` while workers write can tear it (the WAL
holds the newest pages beside it); SQLite's online backup API copies committed pages only, page by page,
under the database's own locks, so a backup taken while the service runs is a state the service was in.
A name ending ``.gz`` is gzip-compressed (a stored campaign shrinks to about 40 %). ``without_curves`` drops
each job result's raw curves (the time series behind its values, nearly all of a battery's stored result) and
keeps everything a campaign reads (values, properties, provenance, designs, reports): a campaign carried to
another machine that way resumes and reports as it would have, and only the curve plots of its jobs are gone
(11 tier B screening batteries: 3.1 MB gzip'd with curves, 21 kB without).

Restore checks before it writes anything: the file must be a SQLite database that passes
``PRAGMA integrity_check`` and carries a demcal schema revision, and an existing target is only replaced
with ``force`` (its old file kept beside it as ``.before-restore``). The restored database is then brought to
the head revision, so a backup from an older release opens in this one. Jobs that were running at the backup
are leased to workers that no longer exist; the queue's expired-lease rule hands them out again.

PostgreSQL has its own tools (``pg_dump``/``pg_restore``); this module says so instead of half-doing them.
"""
from __future__ import annotations

import gzip
import json
import os
import shutil
import sqlite3
import tempfile
from pathlib import Path

from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError

from service.storage import StorageError

# The suffix that asks for gzip, on backup and restore alike.
GZIP_SUFFIX = ".gz"
# Pages copied per step of the online backup: small steps let workers write between them.
PAGES_PER_STEP = 256
# Where a replaced database is kept on a forced restore.
KEPT_SUFFIX = ".before-restore"


def sqlite_path(database_url: str) -> Path:
    """The file of a SQLite URL, or StorageError naming why this URL cannot be backed up here."""
    try:
        url = make_url(database_url)
    except ArgumentError as exc:
        raise StorageError(f"not a database URL: {database_url}") from exc
    if url.get_backend_name() != "sqlite":
        raise StorageError(f"{url.get_backend_name()} database: use its own tools (pg_dump / pg_restore for "
                           "PostgreSQL); demcal db backup copies the embedded SQLite database")
    if not url.database or url.database == ":memory:":
        raise StorageError("an in-memory database has nothing to back up")
    return Path(url.database)


def backup(database_url: str, destination: str | os.PathLike, without_curves: bool = False) -> dict:
    """Copy the database's committed state to ``destination`` (gzip when it ends in .gz); returns sizes and,
    with ``without_curves``, how many results lost their curves."""
    source = sqlite_path(database_url)
    if not source.is_file():
        raise StorageError(f"database {source} does not exist")
    destination = Path(destination)
    if destination.resolve() == source.resolve():
        raise StorageError("the backup would overwrite the database itself")
    destination.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=destination.parent) as scratch:
        copy = Path(scratch) / "copy.db"
        _online_copy(source, copy)
        stripped = _drop_curves(copy) if without_curves else 0
        pages = _check(copy)
        final = Path(scratch) / "final"
        if destination.name.endswith(GZIP_SUFFIX):
            with open(copy, "rb") as raw, gzip.open(final, "wb", compresslevel=6) as packed:
                shutil.copyfileobj(raw, packed)
        else:
            copy.replace(final)
        os.replace(final, destination)  # atomic: a reader never sees half a backup
    return {"database": str(source), "backup": str(destination), "pages": pages,
            "bytes": destination.stat().st_size, "curves_dropped": stripped}


def restore(backup_file: str | os.PathLike, database_url: str, force: bool = False) -> dict:
    """Put a backup in the database's place after checking it; returns the schema revision it is at."""
    from service.migrate import upgrade

    target = sqlite_path(database_url)
    backup_file = Path(backup_file)
    if not backup_file.is_file():
        raise StorageError(f"backup {backup_file} does not exist")
    if target.exists() and target.stat().st_size > 0 and not force:
        raise StorageError(f"database {target} exists; stop the service and pass --force to replace it "
                           f"(the old file is kept as {target.name}{KEPT_SUFFIX})")
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent) as scratch:
        staged = Path(scratch) / "restored.db"
        _unpack(backup_file, staged)
        _check(staged, require_schema=True)
        if target.exists():
            os.replace(target, target.with_name(target.name + KEPT_SUFFIX))
        for side in ("-wal", "-shm"):  # the old database's log must not be replayed onto the restored one
            Path(f"{target}{side}").unlink(missing_ok=True)
        os.replace(staged, target)
    revision = upgrade(f"sqlite:///{target.as_posix()}")
    return {"database": str(target), "backup": str(backup_file), "revision": revision}


def _online_copy(source: Path, copy: Path) -> None:
    src = sqlite3.connect(f"file:{source.as_posix()}?mode=ro", uri=True, timeout=30.0)
    try:
        dst = sqlite3.connect(copy)
        try:
            src.backup(dst, pages=PAGES_PER_STEP)
            dst.execute("PRAGMA journal_mode=DELETE")  # one self-contained file
        finally:
            dst.close()
    except sqlite3.Error as exc:
        raise StorageError(f"database {source} could not be read: {exc}") from exc
    finally:
        src.close()


def _drop_curves(copy: Path) -> int:
    """Remove ``curves`` from every job result of the copy (never the live database), then VACUUM.

    The text is rewritten with Python's json, as SQLAlchemy writes a JSON column on SQLite (NaN kept as NaN)."""
    conn = sqlite3.connect(copy)
    try:
        ids = [row[0] for row in conn.execute("SELECT id FROM jobs WHERE result IS NOT NULL")]
        dropped = 0
        for job_id in ids:  # one row at a time: a campaign's results together are hundreds of MB as objects
            result = json.loads(conn.execute("SELECT result FROM jobs WHERE id = ?", (job_id,)).fetchone()[0])
            if isinstance(result, dict) and result.pop("curves", None) is not None:
                conn.execute("UPDATE jobs SET result = ? WHERE id = ?", (json.dumps(result), job_id))
                dropped += 1
        conn.commit()
        conn.execute("VACUUM")
    finally:
        conn.close()
    return dropped


def _unpack(backup_file: Path, staged: Path) -> None:
    with open(backup_file, "rb") as probe:
        gzipped = probe.read(2) == b"\x1f\x8b"
    try:
        with (gzip.open(backup_file, "rb") if gzipped else open(backup_file, "rb")) as raw, open(staged, "wb") as out:
            shutil.copyfileobj(raw, out)
    except (OSError, EOFError) as exc:
        raise StorageError(f"backup {backup_file} cannot be read: {exc}") from exc


def _check(path: Path, require_schema: bool = False) -> int:
    """Integrity check (and, for a restore, a demcal schema revision); returns the page count."""
    try:
        conn = sqlite3.connect(f"file:{path.as_posix()}?mode=ro", uri=True)
        try:
            verdict = conn.execute("PRAGMA integrity_check").fetchone()[0]
            pages = conn.execute("PRAGMA page_count").fetchone()[0]
            revision = None
            if require_schema:
                has = conn.execute("SELECT 1 FROM sqlite_master WHERE type='table' "
                                   "AND name='alembic_version'").fetchone()
                revision = conn.execute("SELECT version_num FROM alembic_version").fetchone() if has else None
        finally:
            conn.close()
    except sqlite3.DatabaseError as exc:
        raise StorageError(f"not a SQLite database: {exc}") from exc
    if verdict != "ok":
        raise StorageError(f"integrity check failed: {verdict}")
    if require_schema and not revision:
        raise StorageError("a SQLite database, but not a demcal one (no schema revision)")
    return int(pages)
