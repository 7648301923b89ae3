"""Job and campaign statuses: enums that are their stored strings, and no status literal left
outside service/vocabulary.py (calibration/'s loop words: tests/calibration/test_vocabulary.py)."""
from __future__ import annotations

import ast
import json
from pathlib import Path

from sqlalchemy import text

from engine.lab.spec import JobSpec
from service import queue
from service.cli import build_parser
from service.models.campaign import CAMPAIGN_STATUSES
from service.models.job import FINISHED_STATUSES, JOB_STATUSES
from calibration.vocabulary import DiagnosisVerdict, Phase, RunKind, StopReason, Verdict
from service.vocabulary import CampaignStatus, JobStatus

REPO = Path(__file__).resolve().parents[2]
SERVICE = REPO / "service"
PHRASES = {v.value for v in Verdict} | {v.value for v in DiagnosisVerdict} | {v.value.strip() for v in StopReason}
LOOP_WORDS = {v.value for v in Phase} | {v.value for v in RunKind}
ROLE_KEYWORDS = {"phase", "kind", "source", "to"}
WORDS = set(JobStatus.values()) | set(CampaignStatus.values())
# Strings that spell a status word but name something else.
NOT_STATUSES = {
    ("workers/dask_executor.py", "cancelled"): "a key of the task's own cancel cache",
    ("workers/dask_executor.py", "running"): "a Dask client's status",
}


def test_members_are_their_stored_strings_in_text_json_and_comparisons():
    assert JobStatus.values() == JOB_STATUSES == ("queued", "running", "succeeded", "failed", "cancelled")
    assert CampaignStatus.values() == CAMPAIGN_STATUSES == ("draft", "running", "paused", "completed", "failed")
    assert FINISHED_STATUSES == ("succeeded", "failed", "cancelled")
    for member in (*JobStatus, *CampaignStatus):
        assert member == member.value and str(member) == f"{member}" == f"{member:s}" == member.value
        assert json.dumps({"status": member}) == json.dumps({"status": member.value})
    assert JobStatus("failed") is JobStatus.FAILED and CampaignStatus.RUNNING == JobStatus.RUNNING


def test_the_database_holds_the_plain_strings(session_factory):
    with session_factory() as s:
        job = queue.submit_job(s, JobSpec(), evaluator="analytic")
        queue.cancel_job(s, job.id)
        stored = s.execute(text("SELECT status FROM jobs WHERE id = :i"), {"i": job.id}).scalar()
        assert stored == "cancelled" and type(stored) is str
        assert queue.get_job(s, job.id).status == JobStatus.CANCELLED
        assert queue.list_jobs(s, status=JobStatus.CANCELLED)[1] == 1


def test_the_cli_offers_the_enums_values():
    parser = build_parser()
    assert parser.parse_args(["job", "list", "--status", "cancelled"]).status == "cancelled"
    assert parser.parse_args(["campaign", "list", "--status", "paused"]).status == "paused"


def _docstrings(tree: ast.AST) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                ids.add(id(first.value))
    return ids


def test_no_status_literal_outside_the_vocabulary():
    found = []
    for path in sorted(SERVICE.rglob("*.py")):
        relative = path.relative_to(SERVICE).as_posix()
        if relative == "vocabulary.py":
            continue
        tree = ast.parse(path.read_text())
        docs = _docstrings(tree)
        for node in ast.walk(tree):
            if (isinstance(node, ast.Constant) and node.value in WORDS and id(node) not in docs
                    and (relative, node.value) not in NOT_STATUSES):
                found.append(f"{relative}:{node.lineno} {node.value!r}")
    assert found == []


def _constants(node: ast.AST):
    for sub in ast.walk(node):
        if isinstance(sub, ast.Constant) and isinstance(sub.value, str):
            yield sub


def literals(path: Path) -> list[str]:
    tree = ast.parse(path.read_text())
    docs = _docstrings(tree)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docs:
            if node.value.strip() in PHRASES:
                found.append(f"{node.lineno} {node.value!r}")
        if isinstance(node, ast.Compare):
            for op, left, right in zip(node.ops, [node.left, *node.comparators], node.comparators):
                if isinstance(op, (ast.Eq, ast.NotEq)):
                    operands = [left, right]
                elif isinstance(op, (ast.In, ast.NotIn)) and isinstance(right, (ast.Tuple, ast.List, ast.Set)):
                    operands = [right]  # membership in a literal collection (a key looked up in a dict is fine)
                else:
                    continue
                found += [f"{c.lineno} {c.value!r} compared" for o in operands for c in _constants(o)
                          if c.value in LOOP_WORDS]
        if isinstance(node, ast.keyword) and node.arg in ROLE_KEYWORDS:
            found += [f"{c.lineno} {node.arg}={c.value!r}" for c in _constants(node.value) if c.value in LOOP_WORDS]
    return found


def test_the_scan_finds_what_it_looks_for(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text('x = "calibrated"\nif it.phase == "report": pass\nRun(kind="polish")\nd = {"report": 1}\n')
    assert literals(sample) == ["1 'calibrated'", "2 'report' compared", "3 kind='polish'"]


def test_no_loop_word_outside_the_vocabulary():
    found = []
    for package in ("calibration", "service"):
        for path in sorted((REPO / package).rglob("*.py")):
            if path == REPO / "calibration" / "vocabulary.py":
                continue
            found += [f"{path.relative_to(REPO)}:{hit}" for hit in literals(path)]
    assert found == []
