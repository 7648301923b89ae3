"""JSON has no NaN or infinity: one place that turns them into null on the way out.

Why: a stored row with a diverged curve point or a value written before validation existed must be
shown (as null), never turn its whole listing into a 500. New input cannot hold them (the schemas
refuse non-finite numbers); this guards what is already stored and what the engine produces.
"""
from __future__ import annotations

import math
from typing import Any


def json_safe(value: Any) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value
