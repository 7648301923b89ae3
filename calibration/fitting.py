"""Response surfaces of the targets over a design (doe.fit), fitted once per design.

Each target is matched to the runs' responses by its key; a target no run produced is "not
simulated", one the factors do not move is "not modelled" (reported, not fatal). The pure error of
centre replicates is the simulator's seed-to-seed scatter. A response some runs lack is fitted on the
runs that hold it, with a smaller model where those cannot estimate the full one (doe.missing), and on a
log scale where Box-Cox rejects the plain one (doe.transform: a modulus is a power law of a log-scaled
contact modulus); the report repeats both beside the target.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from doe.designs import Design
from doe.factors import DoeError
from doe.fit import ResponseFit, pure_error
from doe.missing import fit_available

from .keys import ResponseKey, find
from .records import Measured


@dataclass
class TargetModel:
    target: Measured
    key: ResponseKey | None               # the simulated response it matched (None: not simulated)
    values: list[float] = field(default_factory=list)  # per run, std order
    fit: ResponseFit | None = None
    error: str | None = None
    pure_error_sd: float | None = None
    pure_error_df: int = 0

    @property
    def status(self) -> str:
        if self.key is None:
            return "not_simulated"
        return "modelled" if self.fit is not None else "not_modelled"

    def to_dict(self) -> dict[str, Any]:
        t = self.target.key
        out = {"test": t.test, "quantity": t.quantity, "condition": t.condition_dict, "unit": self.target.unit,
               "measurement_id": self.target.id, "response": None if self.key is None else self.key.name,
               "status": self.status, "ok": self.fit is not None, "error": self.error,
               "pure_error_sd": self.pure_error_sd,
               "values": [None if not math.isfinite(v) else float(v) for v in self.values]}
        if self.fit is not None:
            out["fit"] = self.fit.to_dict()
        return out


def run_values(records: Sequence[dict]) -> dict[ResponseKey, float]:
    return {ResponseKey.from_record(r): float(r["value"]) for r in records}


def fit_targets(design: Design, runs: Sequence[Sequence[dict]], targets: Sequence[Measured]) -> list[TargetModel]:
    """Fit every target over ``design``; ``runs`` are the runs' records in standard order."""
    if len(runs) != design.n_runs:
        raise ValueError(f"{len(runs)} runs for a design of {design.n_runs}")
    values = [run_values(r) for r in runs]
    # every response any run gave (the first run may lack one that a hold at its corner could not settle)
    produced = list(dict.fromkeys(k for v in values for k in v))
    out = []
    for target in targets:
        key = find(produced, target.key)
        model = TargetModel(target, key)
        out.append(model)
        if key is None:
            model.error = "the battery produced no value for this test, quantity and condition"
            continue
        y = np.array([v.get(key, math.nan) for v in values], dtype=float)
        model.values = y.tolist()
        ss_pe, df_pe = pure_error(design.coded[np.isfinite(y)], y[np.isfinite(y)])
        model.pure_error_df = int(df_pe)
        model.pure_error_sd = math.sqrt(ss_pe / df_pe) if df_pe > 0 else None
        finite = y[np.isfinite(y)]
        if finite.size == 0 or np.ptp(finite) <= 1e-12 * max(1.0, float(np.max(np.abs(finite)))):
            model.error = "the response does not change over the design; the factors do not move it"
            continue
        try:
            model.fit = fit_available(design, y, response=key.name)
        except DoeError as exc:
            model.error = str(exc)
    return out
