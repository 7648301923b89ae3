"""``demcal db backup`` / ``db restore``: a consistent copy while a writer holds a transaction, and a restore that
checks before it writes and never loses the database it replaces."""
from __future__ import annotations

import gzip
import sqlite3
import subprocess
import sys

import pytest

from engine.lab.spec import JobSpec
from service import queue
from service.backup import KEPT_SUFFIX, backup, restore
from service.db import make_engine, make_session_factory
from service.migrate import head_revision, upgrade
from service.storage import StorageError


def _database(path, seeds) -> str:
    url = f"sqlite:///{path}"
    upgrade(url)
    engine = make_engine(url)
    try:
        with make_session_factory(engine)() as s:
            for seed in seeds:
                queue.submit_job(s, JobSpec(seed=seed), evaluator="analytic")
    finally:
        engine.dispose()
    return url


def _seeds(path) -> list[int]:
    conn = sqlite3.connect(path)
    try:
        return sorted(int(row[0]) for row in conn.execute("SELECT json_extract(spec, '$.seed') FROM jobs"))
    finally:
        conn.close()


def test_backup_holds_committed_rows_only_and_restores_them(tmp_path):
    url = _database(tmp_path / "live.db", [1, 2, 3])
    writer = sqlite3.connect(tmp_path / "live.db", isolation_level=None)
    writer.execute("BEGIN IMMEDIATE")  # a worker mid-write: its row must not be in the copy
    writer.execute("DELETE FROM jobs WHERE json_extract(spec, '$.seed') = 2")
    try:
        done = backup(url, tmp_path / "b" / "copy.db.gz")
    finally:
        writer.execute("ROLLBACK")
        writer.close()
    assert done["pages"] > 0
    with gzip.open(tmp_path / "b" / "copy.db.gz") as packed:
        assert packed.read(16) == b"SQLite format 3\x00"
    target = tmp_path / "elsewhere" / "demcal.db"
    restored = restore(tmp_path / "b" / "copy.db.gz", f"sqlite:///{target}")
    assert restored["revision"] == head_revision()
    assert _seeds(target) == [1, 2, 3]


def test_restore_refuses_to_replace_without_force_and_keeps_the_old_file(tmp_path):
    old = _database(tmp_path / "old.db", [7])
    _database(tmp_path / "other.db", [8, 9])
    backup(f"sqlite:///{tmp_path / 'other.db'}", tmp_path / "other.bak")
    with pytest.raises(StorageError, match="--force"):
        restore(tmp_path / "other.bak", old)
    assert _seeds(tmp_path / "old.db") == [7]
    restore(tmp_path / "other.bak", old, force=True)
    assert _seeds(tmp_path / "old.db") == [8, 9]
    assert _seeds(tmp_path / ("old.db" + KEPT_SUFFIX)) == [7]


def test_bad_backups_are_refused_before_anything_is_written(tmp_path):
    target = _database(tmp_path / "keep.db", [4])
    (tmp_path / "text.db").write_text("not a database")
    plain = sqlite3.connect(tmp_path / "plain.db")
    plain.execute("CREATE TABLE t (x)")
    plain.commit()
    plain.close()
    for bad, needle in [("text.db", "not a SQLite database"), ("plain.db", "not a demcal one"),
                        ("missing.db", "does not exist")]:
        with pytest.raises(StorageError, match=needle):
            restore(tmp_path / bad, target, force=True)
        assert _seeds(tmp_path / "keep.db") == [4]
    with pytest.raises(StorageError, match="pg_dump"):
        backup("postgresql://u@localhost/demcal", tmp_path / "x.db")
    with pytest.raises(StorageError, match="does not exist"):
        backup(f"sqlite:///{tmp_path / 'none.db'}", tmp_path / "x.db")
    with pytest.raises(StorageError, match="overwrite the database itself"):
        backup(target, tmp_path / "keep.db")


def test_cli_backup_and_restore_print_one_line(tmp_path):
    _database(tmp_path / "a.db", [5])

    def run(*args):
        return subprocess.run([sys.executable, "-m", "service.cli", "db", *args], capture_output=True, text=True,
                              timeout=60)

    for action in ("backup", "restore"):  # the help itself prints (a bare % in it once raised a TypeError)
        shown = run(action, "--help")
        assert shown.returncode == 0 and "usage" in shown.stdout and "Traceback" not in shown.stderr
    done = run("backup", str(tmp_path / "a.db.gz"), "--db", str(tmp_path / "a.db"))
    assert done.returncode == 0 and "backed up" in done.stdout, done.stderr
    done = run("restore", str(tmp_path / "a.db.gz"), "--db", str(tmp_path / "a.db"))
    assert done.returncode == 1 and "--force" in done.stderr and "Traceback" not in done.stderr
    done = run("restore", str(tmp_path / "a.db.gz"), "--db", str(tmp_path / "b.db"))
    assert done.returncode == 0 and head_revision() in done.stdout, done.stderr
    assert _seeds(tmp_path / "b.db") == [5]


def test_backup_without_curves_keeps_every_value_and_leaves_the_live_database_whole(tmp_path):
    import json
    import math

    _database(tmp_path / "live.db", [1, 2])
    result = {"properties": {"bulk_density_kg_m3": 1550.0, "angle_deg": math.nan},
              "curves": {"dst_10500": {"shear_displacement_m": [0.0, 0.001], "shear_stress_pa": [0.0, 5e3]}}}
    conn = sqlite3.connect(tmp_path / "live.db")
    conn.execute("UPDATE jobs SET result = ? WHERE json_extract(spec, '$.seed') = 1", (json.dumps(result),))
    conn.commit()
    conn.close()
    done = backup(f"sqlite:///{tmp_path / 'live.db'}", tmp_path / "lean.db.gz", without_curves=True)
    assert done["curves_dropped"] == 1
    restore(tmp_path / "lean.db.gz", f"sqlite:///{tmp_path / 'back.db'}")

    def stored(path):
        conn = sqlite3.connect(path)
        try:
            text = conn.execute("SELECT result FROM jobs WHERE json_extract(spec, '$.seed') = 1").fetchone()[0]
        finally:
            conn.close()
        return json.loads(text)

    lean = stored(tmp_path / "back.db")
    assert "curves" not in lean and lean["properties"]["bulk_density_kg_m3"] == 1550.0
    assert math.isnan(lean["properties"]["angle_deg"])
    assert stored(tmp_path / "live.db")["curves"] == result["curves"]  # the live database keeps its curves
