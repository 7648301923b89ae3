"""The loop's words are spelt once: no verdict, stop reason, phase or run-kind literal outside
calibration/vocabulary.py.

Verdicts and stop reasons are phrases no other string shares, so any literal spelling one is flagged.
Phase and run-kind words ("design", "report", "diagnosis", ...) are also the keys of the iteration's
stored products, so those are flagged where they are used as a phase or a kind: compared with
something (==, !=, in a literal collection), or passed as ``phase=``, ``kind=`` or ``source=``/``to=``.
"""
from __future__ import annotations

import ast
from pathlib import Path

from calibration.vocabulary import Phase, RunKind, StopReason, Verdict

ROOT = Path(__file__).resolve().parents[2]
PHRASES = {v.value for v in Verdict} | {v.value.strip() for v in StopReason}
WORDS = {v.value for v in Phase} | {v.value for v in RunKind}
ROLE_KEYWORDS = {"phase", "kind", "source", "to"}


def _docstrings(tree: ast.AST) -> set[int]:
    ids = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                ids.add(id(first.value))
    return ids


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
                          if c.value in WORDS]
        if isinstance(node, ast.keyword) and node.arg in ROLE_KEYWORDS:
            found += [f"{c.lineno} {node.arg}={c.value!r}" for c in _constants(node.value) if c.value in WORDS]
    return found


def test_the_scan_finds_what_it_looks_for(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text('x = "calibrated"\nif it.phase == "report": pass\nRun(kind="polish")\nd = {"report": 1}\n')
    assert literals(sample) == ["1 'calibrated'", "2 'report' compared", "3 kind='polish'"]


def test_no_loop_word_outside_the_vocabulary():
    found = []
    for package in ("calibration", "service"):
        for path in sorted((ROOT / package).rglob("*.py")):
            if path == ROOT / "calibration" / "vocabulary.py":
                continue
            found += [f"{path.relative_to(ROOT)}:{hit}" for hit in literals(path)]
    assert found == []
