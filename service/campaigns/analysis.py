"""Fit each target's response over the design and optimise against the measurements (doe/).

The campaign's targets are the material's measurements that the battery simulates,
matched on (test, quantity, condition). A response doe/ cannot model (e.g. one the
factors do not move at all) is reported as such instead of failing the campaign.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from doe.designs import Design
from doe.factors import DoeError
from doe.fit import fit_response, pure_error

from service.campaigns.responses import find_response


class AnalysisError(Exception):
    pass


def target_uncertainty(meas, default_relative: float) -> tuple[float, bool]:
    """Standard uncertainty of a target and whether it was assumed (no replicates published)."""
    u = meas.standard_uncertainty
    if u is not None and u > 0:
        return float(u), False
    return abs(meas.mean) * default_relative, True


def fit_targets(design: Design, runs, targets) -> tuple[dict[str, Any], dict[str, Any], dict[str, Any]]:
    """Returns (models JSON by response, fit objects by response, target by response)."""
    by_std = sorted(runs, key=lambda r: r.std_order)
    if [r.std_order for r in by_std] != list(range(1, design.n_runs + 1)):
        raise AnalysisError("design runs do not match the stored design")
    models: dict[str, Any] = {}
    fits: dict[str, Any] = {}
    matched: dict[str, Any] = {}
    first = by_std[0].responses or {}
    for meas in targets:
        name = find_response(first, meas.test, meas.quantity, meas.condition)
        if name is None or name in matched:
            continue
        matched[name] = meas
        entry: dict[str, Any] = {"test": meas.test, "quantity": meas.quantity, "condition": dict(meas.condition),
                                 "unit": meas.unit, "measurement_id": meas.id}
        y = np.array([float((r.responses or {}).get(name, {}).get("value", math.nan)) for r in by_std])
        ss_pe, df_pe = pure_error(design.coded, y)
        entry["pure_error_sd"] = math.sqrt(ss_pe / df_pe) if df_pe > 0 else None
        entry["values"] = [None if not math.isfinite(v) else float(v) for v in y]
        if np.nanmax(y) - np.nanmin(y) <= 1e-12 * max(1.0, float(np.nanmax(np.abs(y)))):
            entry.update(ok=False, error="the response does not change over the design; the factors do not move it")
        else:
            try:
                fit = fit_response(design, y, response=name)
                fits[name] = fit
                entry.update(ok=True, error=None, fit=fit.to_dict())
            except DoeError as exc:
                entry.update(ok=False, error=str(exc))
        models[name] = entry
    return models, fits, matched
