"""schemathesis against a live ``demcal serve``: no server errors, no schema violations, no undocumented
status codes (issue 13), with every check (``--checks all``) and every phase, the stateful one following the
document's links (issue 32), on SQLite and on PostgreSQL. Seeded and bounded, so CI runs the same cases every time.

It runs the ``schemathesis`` command (the test dependency) on the service's own OpenAPI document, with
the bundled material seeded so that reads, copies and refused writes of real rows are exercised too.
"""
from __future__ import annotations

import re
import shutil
import subprocess
import sys

import pytest

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)

SEED = 13
MAX_EXAMPLES = 10  # per operation and phase; ~40 operations
# Every check. positive_data_acceptance is told that schema-valid input may be refused with 422: a schema
# cannot say every rule that joins fields or looks up rows (the particle limit, a quantity's bounds given its
# test); test_fuzz_stateful.py checks that such a 422 names only those rules.
CHECKS = "all"
# The stateful phase's chains must be long enough to reach the rows they create through the links, with
# some 56 operations sharing its budget (rigs and exports joined the document).
CONFIG = """[checks.positive_data_acceptance]
expected-statuses = ["2xx", "3xx", "401", "403", "404", "409", "422", "429"]

[phases.stateful]
max-steps = 30
"""


def schemathesis_cmd() -> list[str]:
    exe = shutil.which("schemathesis") or shutil.which("st")
    if exe is None:
        pytest.fail("schemathesis is a test dependency: pip install -e '.[test]'")
    return [exe]


@pytest.mark.slow  # ~2 min on two busy cores; CI runs it (it runs every test)
def test_schemathesis_finds_no_server_errors_or_contract_violations(live_server, tmp_path):
    base, _, proc = live_server(workers=0, DEMCAL_SEED_MATERIALS="true")
    report = tmp_path / "junit.xml"
    (tmp_path / "schemathesis.toml").write_text(CONFIG)  # read from the working directory
    run = subprocess.run(
        [*schemathesis_cmd(), "run", f"{base}/api/v1/openapi.json", "--checks", CHECKS,
         "--max-examples", str(MAX_EXAMPLES), "--seed", str(SEED), "--workers", "1",
         "--report", "junit", "--report-junit-path", str(report)],
        capture_output=True, text=True, timeout=1200, cwd=tmp_path)  # its cache dir goes there, not in the repo
    output = run.stdout + run.stderr
    summary = re.search(r"(\d+) generated, (.*)", output)
    print(summary.group(0) if summary else output[-3000:], file=sys.stderr)
    assert run.returncode == 0, output[-6000:]
    assert summary is not None and "passed" in summary.group(2)
    assert int(summary.group(1)) >= 40 * MAX_EXAMPLES // 2  # it really generated cases for every operation
    links = re.search(r"API Links:\s+(\d+) covered", output)  # the stateful phase ran and followed links
    # (its chains, and a bigger stateful run with the custom check, are test_fuzz_stateful.py's)
    assert links is not None and int(links.group(1)) >= 5, output[-3000:]
    assert proc.poll() is None  # the server is still up
