"""README.md runs as written: its stand-in command blocks, in order, against a live ``demcal serve``.

The commands are read from README.md itself (the fenced block after each ``<!-- readme-test: ... -->``
marker), so the README and this test cannot drift apart. They run in one bash with ``set -euo pipefail``:
every command must exit 0, and ids captured in one block (``campaign=$(demcal ... -q)``) are used in
the next, as a reader's shell would. ``demcal`` is this checkout's CLI, and the service is found through
DEMCAL_PORT alone, as a reader who moved the server with it would find it.
"""
from __future__ import annotations

import csv
import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

from browser_support import stop_service
from service_net import free_port, wait_healthy

REPO = Path(__file__).resolve().parents[2]
README = REPO / "README.md"
# where each marked block runs: the service's blocks from a folder of their own, to show they need no
# files; the designed-experiment block from the repository's root, whose docs/examples it reads
WHERE = {"from an empty folder, against the service": "empty", "from the repository's root": "repo"}
BLOCK = re.compile(r"<!-- readme-test: (?P<where>[^>]*?) -->\n```bash\n(?P<code>.*?)\n```", re.S)


def marked_blocks(text: str) -> list[tuple[str, str, str]]:
    """(section heading, where, code) of every marked block, in README order."""
    out = []
    for match in BLOCK.finditer(text):
        heading = re.findall(r"^## (.+)$", text[:match.start()], re.M)[-1]
        assert match["where"] in WHERE, f"unknown readme-test marker {match['where']!r}"
        out.append((heading, WHERE[match["where"]], match["code"]))
    return out


def test_the_marked_blocks_cover_the_cli_and_the_loop():
    text = README.read_text()
    blocks = marked_blocks(text)
    assert text.count("<!-- readme-test:") == len(blocks)  # a marker without its block runs nothing: refuse it
    sections = {heading for heading, _, _ in blocks}
    assert {"Using it", "The calibration loop, step by step"} <= sections
    code = "\n".join(c for _, _, c in blocks)
    assert "demcal campaign iterate" in code and "demcal material delete" in code
    # set -e does not see a failure on the left of && or ||: every command on its own
    assert not re.search(r"&&|\|\|", code)
    assert "--evaluator dem" not in code  # the stand-in only: the test must stay fast


def test_the_example_runs_file_is_the_thesis_table():
    """docs/examples/thesis-a9-runs.csv is Table A9 as transcribed for the doe tests, number for number."""
    table = json.loads((REPO / "tests" / "doe" / "thesis_appendix_a.json").read_text())["table_A9_responses"]["runs"]
    with (REPO / "docs" / "examples" / "thesis-a9-runs.csv").open() as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    assert [r["run"] for r in rows] == [t["run"] for t in table]
    for row, printed in zip(rows, table):
        assert {k: float(v) for k, v in row.items() if k != "run"} == {k: float(v) for k, v in printed.items()
                                                                       if k != "run"}


def test_readme_stand_in_commands_run_in_order_from_an_empty_folder(tmp_path):
    empty, data, bin_dir = (tmp_path / name for name in ("empty", "data", "bin"))
    for folder in (empty, data, bin_dir):
        folder.mkdir()
    demcal = bin_dir / "demcal"  # the reader's `demcal`, on this checkout's code
    demcal.write_text(f"#!/bin/sh\nexec {shlex.quote(sys.executable)} -m service.cli \"$@\"\n")
    demcal.chmod(0o755)
    port = free_port()
    env = {k: v for k, v in os.environ.items() if k not in ("DEMCAL_URL", "DEMCAL_HOST", "DEMCAL_TOKEN")}
    env.update({"PYTHONPATH": str(REPO), "PATH": f"{bin_dir}{os.pathsep}{env.get('PATH', '')}",
                "DEMCAL_PORT": str(port), "DEMCAL_DATABASE_URL": f"sqlite:///{(data / 'demcal.db').as_posix()}",
                "DEMCAL_WORKERS": "1", "DEMCAL_TICK_INTERVAL_S": "0.3", "DEMCAL_POLL_INTERVAL_S": "0.1",
                "DEMCAL_LOG_LEVEL": "WARNING", "PYTHONUNBUFFERED": "1"})
    server = subprocess.Popen([sys.executable, "-m", "service.cli", "serve"], env=env, cwd=data)
    try:
        wait_healthy(f"http://127.0.0.1:{port}", server)
        lines = ["set -euo pipefail", "set -x"]
        for _, where, code in marked_blocks(README.read_text()):
            lines += [f"cd {shlex.quote(str(empty if where == 'empty' else REPO))}", code]
        done = subprocess.run(["bash", "-c", "\n".join(lines)], env=env, capture_output=True, text=True, timeout=600)
    finally:
        stop_service(server)
    traced = [line for line in done.stderr.splitlines() if line.startswith("+")]
    assert done.returncode == 0, (f"README command failed (exit {done.returncode}): "
                                  f"{traced[-1] if traced else '?'}\n{done.stderr[-2000:]}")
    # what the README says it prints: it stopped because the model fits (the lack of fit passes, or the
    # diagnosis over every battery at the optimum finds no misfit left)
    assert re.search(r"automatic mode stopped: (lack of fit passes|diagnosis: no misfit)", done.stdout), done.stdout[-500:]
    assert list(empty.iterdir()) == []  # the commands need no files and leave none
