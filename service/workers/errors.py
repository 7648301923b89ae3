"""What a failed job tells its users: one clear line, no traceback, no server paths.

Why: a job's ``error`` is readable by anyone who can read the job (reads need no token), and a
traceback shows the server's file layout and code. The full traceback goes to the worker's log,
where the operator finds it by job id; the stored message is the exception's type and text.
"""
from __future__ import annotations

import re

MAX_MESSAGE = 2000
# Absolute POSIX or Windows paths (/home/x/y.py, C:\\x\\y) inside a message.
_PATH = re.compile(r"(?:(?<=[\s'\"(=])|^)(?:/[^\s'\":,()]+){2,}|[A-Za-z]:\\[^\s'\":,()]+")
_TRACEBACK = "Traceback (most recent call last)"


def scrub(message: str) -> str:
    """Drop any traceback, replace absolute paths by their last part, keep it short."""
    head = message.split(_TRACEBACK, 1)[0].strip()
    head = _PATH.sub(lambda m: "<path>/" + re.split(r"[/\\]", m.group(0))[-1], head)
    if len(head) > MAX_MESSAGE:
        head = head[:MAX_MESSAGE - 3] + "..."
    return head or "the job failed (details in the server log)"


def public_error(exc: BaseException) -> str:
    """``Type: message`` of ``exc``, scrubbed; pydantic's multi-line errors stay readable."""
    text = str(exc).strip()
    return scrub(f"{type(exc).__name__}: {text}" if text else type(exc).__name__)
