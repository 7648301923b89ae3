"""Where a request carries a NUL character (U+0000), for a 422 that names it.

Why: PostgreSQL's text columns cannot hold NUL ("text fields cannot contain NUL (0x00) bytes"), so there a
name, a source or an idempotency key holding one, even in a lookup, answered 500; SQLite stored it. No field
of this API has a use for NUL, so a request carrying one is refused the same way on both stores: in the
path, a query parameter, or any string (or key) of a JSON body, escaped as ``\\u0000``.
"""
from __future__ import annotations

import json
from typing import Any
from urllib.parse import parse_qsl

NUL = "\x00"


def in_query(query_string: bytes) -> str | None:
    """The name of the first query parameter whose name or value holds NUL; None when none does."""
    if b"%00" not in query_string:
        return None
    for name, value in parse_qsl(query_string.decode("latin-1"), keep_blank_values=True):
        if NUL in name or NUL in value:
            return name.replace(NUL, "")
    return None


def _find(value: Any, path: list) -> list | None:
    if isinstance(value, str):
        return path if NUL in value else None
    if isinstance(value, dict):
        for key, item in value.items():
            if NUL in key:
                return [*path, key.replace(NUL, "")]
            found = _find(item, [*path, key])
            if found is not None:
                return found
    elif isinstance(value, list):
        for index, item in enumerate(value):
            found = _find(item, [*path, index])
            if found is not None:
                return found
    return None


def in_json(body: bytes) -> list | None:
    """The location (keys and indices) of the first string of a JSON body holding NUL; None when none does
    or the body is not JSON (the route's own validation answers that). The body's depth is bounded already."""
    if b"\\u0000" not in body:  # the only way JSON text can carry NUL: a cheap test that skips nearly every body
        return None
    try:
        document = json.loads(body)
    except ValueError:
        return None
    return _find(document, [])
