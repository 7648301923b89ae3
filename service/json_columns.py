"""JSON columns that keep NaN and infinities on PostgreSQL as they are kept on SQLite.

Why: the engine reports a diverged curve point or an undefined statistic as NaN or infinity. SQLite stores
Python's JSON text (``NaN``, ``Infinity``) as it is and gives the floats back; PostgreSQL's ``json`` type
refuses those tokens, so there a job whose result held one could not be completed (the UPDATE failed and
the job with it). On PostgreSQL each non-finite float is stored as ``{"$nonfinite": "NaN"}`` (or
``"Infinity"``, ``"-Infinity"``) and turned back into the float when read, so every reader (the calibration
loop, ``json_safe`` on the way out) sees the same values on both backends. Finite JSON, nearly all of it,
takes the plain ``json`` path both ways.
"""
from __future__ import annotations

import json
import math
from typing import Any

MARKER = "$nonfinite"
_DECODED = {"NaN": math.nan, "Infinity": math.inf, "-Infinity": -math.inf}


def _encode(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return {MARKER: "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")}
    if isinstance(value, dict):
        return {key: _encode(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_encode(item) for item in value]
    return value


def _decode(obj: dict) -> Any:
    if len(obj) == 1 and obj.get(MARKER) in _DECODED:
        return _DECODED[obj[MARKER]]
    return obj


def dumps(value: Any) -> str:
    """Standard JSON text (no NaN token), non-finite floats as marker objects."""
    try:
        return json.dumps(value, allow_nan=False)
    except ValueError:  # a non-finite float somewhere: the slow path, only for such values
        return json.dumps(_encode(value), allow_nan=False)


def loads(text: str | bytes) -> Any:
    """Inverse of ``dumps``."""
    if isinstance(text, (bytes, bytearray)):
        text = text.decode("utf-8")
    if MARKER not in text:
        return json.loads(text)
    return json.loads(text, object_hook=_decode)
