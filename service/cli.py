"""``demcal``: serve the API, run workers, upgrade the database, and the other parts' commands."""
from __future__ import annotations

import argparse
import importlib
import logging
import os
import sys
from pathlib import Path

from pydantic import ValidationError

from service.config import settings_from_env

# Each provides register(subparsers): demcal doe ..., demcal run SPEC, demcal material/campaign/schedule ...
PLUGINS = ("doe.cli", "engine.lab.cli", "service.cli_jobs", "service.cli_campaigns", "service.cli_rigs")


def database_url(value: str | None) -> str | None:
    """``--db`` takes a SQLAlchemy URL or, for convenience, a SQLite file path."""
    if value is None or "://" in value:
        return value
    return f"sqlite:///{Path(value).expanduser().resolve().as_posix()}"


def _settings(args: argparse.Namespace, **extra):
    try:
        return settings_from_env(database_url=database_url(getattr(args, "db", None)), **extra)
    except ValidationError as exc:
        fields = "; ".join(f"{'.'.join(map(str, e['loc']))}: {e['msg']}" for e in exc.errors())
        raise SystemExit(f"demcal: invalid setting ({fields})") from None


def _logging() -> None:
    logging.basicConfig(level=os.environ.get("DEMCAL_LOG_LEVEL", "INFO"),
                        format="%(asctime)s %(process)d %(name)s %(levelname)s %(message)s")


def cmd_serve(args: argparse.Namespace) -> int:
    settings = _settings(args, host=args.host, port=args.port, workers=args.workers,
                         dask_scheduler=args.dask_scheduler)
    from service.security import check_bind  # imports FastAPI: only serve pays for it, not every client command

    check_bind(settings)  # before the heavy imports: refuse a non-loopback host without a token
    from service.storage import StorageError, check_storage

    try:
        check_storage(settings.database_url)  # one line and exit 1, not a traceback, when it cannot be used
    except StorageError as exc:
        print(f"demcal serve: {exc}", file=sys.stderr)
        return 1
    import uvicorn

    from service.app import create_app

    _logging()
    app = create_app(settings)
    uvicorn.run(app, host=settings.host, port=settings.port, proxy_headers=False,  # forwarding headers: service.security.peer_address
                log_level=os.environ.get("DEMCAL_LOG_LEVEL", "info").lower())
    return 0


def cmd_worker(args: argparse.Namespace) -> int:
    from service.storage import StorageError, check_storage
    from service.workers.process import run_worker

    settings = _settings(args, dask_scheduler=args.dask_scheduler)
    try:
        check_storage(settings.database_url)
    except StorageError as exc:
        print(f"demcal worker: {exc}", file=sys.stderr)
        return 1
    _logging()
    return run_worker(settings)


def _db_action(name: str, action) -> int:
    """Run a ``demcal db`` action; its failure is one line on stderr and exit 1 (unreachable server, unknown
    revision, a backup that is not one), never a traceback."""
    from service.storage import StorageError, describe

    try:
        line = action()
    except StorageError as exc:
        print(f"demcal db {name}: {exc}", file=sys.stderr)
        return 1
    except Exception as exc:  # noqa: BLE001 - the driver's or Alembic's, said in one line
        print(f"demcal db {name}: {describe(exc)}", file=sys.stderr)
        return 1
    print(line)
    return 0


def cmd_db_upgrade(args: argparse.Namespace) -> int:
    from service.migrate import upgrade

    url = _settings(args).database_url
    return _db_action("upgrade", lambda: f"database {url} is at revision {upgrade(url, args.revision)}")


def cmd_db_backup(args: argparse.Namespace) -> int:
    from service.backup import backup

    url = _settings(args).database_url

    def action() -> str:
        done = backup(url, args.file, without_curves=args.without_curves)
        dropped = f", curves dropped from {done['curves_dropped']} results" if args.without_curves else ""
        return (f"backed up {done['database']} ({done['pages']} pages) to {done['backup']} ({done['bytes']} "
                f"bytes{dropped})")
    return _db_action("backup", action)


def cmd_db_restore(args: argparse.Namespace) -> int:
    from service.backup import restore

    url = _settings(args).database_url

    def action() -> str:
        done = restore(args.file, url, force=args.force)
        return f"restored {done['backup']} to {done['database']}, at revision {done['revision']}"
    return _db_action("restore", action)


def _db_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--db", metavar="URL", help="SQLAlchemy URL or SQLite file "
                        "(default: $DEMCAL_DATABASE_URL or ./demcal-data/demcal.db)")


def build_parser(plugins: bool = True) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="demcal", description="demcal: calibration service for DEM models")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    serve = sub.add_parser("serve", help="run the API with local workers (or a Dask dispatcher)")
    serve.add_argument("--host", help="bind address (default 127.0.0.1; others need DEMCAL_TOKEN)")
    serve.add_argument("--port", type=int, help="port (default 8000)")
    serve.add_argument("--workers", type=int, help="local worker processes (default: one per core; 0: none)")
    serve.add_argument("--dask-scheduler", metavar="ADDRESS", help="run jobs on this Dask cluster, e.g. tcp://host:8786")
    _db_option(serve)
    serve.set_defaults(func=cmd_serve)

    worker = sub.add_parser("worker", help="run one standalone worker against the same database")
    worker.add_argument("--dask-scheduler", metavar="ADDRESS", help="dispatch claimed jobs to this Dask cluster")
    _db_option(worker)
    worker.set_defaults(func=cmd_worker)

    db = sub.add_parser("db", help="database schema, backup and restore")
    db_sub = db.add_subparsers(dest="db_command", required=True, metavar="ACTION")
    up = db_sub.add_parser("upgrade", help="apply Alembic migrations")
    up.add_argument("--revision", default="head", help="target revision (default head)")
    _db_option(up)
    up.set_defaults(func=cmd_db_upgrade)
    save = db_sub.add_parser("backup", help="copy the SQLite database's committed state to FILE (gzip if FILE "
                             "ends .gz); safe while the service runs")
    save.add_argument("file", metavar="FILE")
    save.add_argument("--without-curves", action="store_true", help="leave out the job results' raw curves (time "
                      "series): everything a campaign reads is kept, in about 1 %% of the space")
    _db_option(save)
    save.set_defaults(func=cmd_db_backup)
    back = db_sub.add_parser("restore", help="check a backup and put it in the database's place (service stopped)")
    back.add_argument("file", metavar="FILE")
    back.add_argument("--force", action="store_true", help="replace an existing database (kept as "
                      "NAME.before-restore)")
    _db_option(back)
    back.set_defaults(func=cmd_db_restore)

    for module_name in PLUGINS if plugins else ():
        importlib.import_module(module_name).register(sub)
    return parser


OWN_COMMANDS = ("serve", "worker", "db")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    # The other parts' commands import heavy libraries (statsmodels, numba); skip them for ours.
    own = bool(argv) and argv[0] in OWN_COMMANDS
    args = build_parser(plugins=not own).parse_args(argv)
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
