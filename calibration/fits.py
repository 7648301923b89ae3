"""Response surfaces fitted once per iteration, however many phases ask for them.

Why a memo keyed by content: an iteration's surfaces are a pure function of its design, the design
batteries' responses and the targets, and every later phase (analysis, each polishing round, the
report, the diagnosis) needs them. The service's runner works from the database alone and may be
restarted between any two phases, so the surfaces are not stored as objects: the first phase to ask
in a process fits them, the others get the same objects back, and after a restart the first ask
refits them exactly (the fit is deterministic). ``FIT_COUNT`` counts the surfaces actually fitted.
"""
from __future__ import annotations

import hashlib
import json
from collections import OrderedDict
from typing import Sequence

from doe.designs import Design

from .fitting import TargetModel, fit_targets
from .records import Measured

_CACHE: "OrderedDict[str, tuple[Design, list[TargetModel]]]" = OrderedDict()
_CACHE_SIZE = 32
FIT_COUNT = {"surfaces": 0}


def _key(design_dict: dict, runs: Sequence[Sequence[dict]], targets: Sequence[Measured]) -> str:
    payload = {
        "design": design_dict,
        "runs": [[(r["test"], r["quantity"], sorted((r.get("condition") or {}).items()), float(r["value"]))
                  for r in run] for run in runs],
        "targets": [(t.key.name, list(t.values), t.stated_uncertainty, t.id) for t in targets],
    }
    return hashlib.sha256(json.dumps(payload, sort_keys=True, default=str).encode()).hexdigest()


def fitted(design_dict: dict, runs: Sequence[Sequence[dict]], targets: Sequence[Measured]
           ) -> tuple[Design, list[TargetModel]]:
    """(design, one TargetModel per target) for ``runs`` (the design's batteries in standard order)."""
    key = _key(design_dict, runs, targets)
    hit = _CACHE.get(key)
    if hit is not None:
        _CACHE.move_to_end(key)
        return hit
    design = Design.from_dict(design_dict)
    models = fit_targets(design, runs, targets)
    FIT_COUNT["surfaces"] += len(models)  # fit_targets tries each target once
    _CACHE[key] = (design, models)
    while len(_CACHE) > _CACHE_SIZE:
        _CACHE.popitem(last=False)
    return design, models


def forget() -> None:
    """Empty the memo and zero the count (a fresh process, as after a restart)."""
    _CACHE.clear()
    FIT_COUNT["surfaces"] = 0
