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
from doe.confirm import confirm
from doe.constraints import Target
from doe.fit import fit_response, pure_error
from doe.optimise import calibrate

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


def _condition_text(condition: dict[str, float]) -> str:
    return ", ".join(f"{k}={v:g}" for k, v in sorted(condition.items()))


def analyse(config, design_dict: dict, runs, targets) -> dict[str, Any]:
    """Fit every matched target, then calibrate (doe.optimise.calibrate) against them."""
    design = Design.from_dict(design_dict)
    models, fits, matched = fit_targets(design, runs, targets)
    doe_targets, by_response = [], {}
    for name, meas in matched.items():
        if name not in fits:
            continue
        u, assumed = target_uncertainty(meas, config.default_relative_uncertainty)
        doe_targets.append(Target(name, meas.mean, u, meas.test, _condition_text(meas.condition)))
        by_response[name] = (meas, u, assumed)
    if not doe_targets:
        unmatched = [f"{m.test}/{m.quantity}" for m in targets if not any(m is v for v in matched.values())]
        raise AnalysisError("no target could be modelled: "
                            + "; ".join([f"{n}: {m['error']}" for n, m in models.items() if not m.get("ok")]
                                        + ([f"not simulated: {', '.join(unmatched)}"] if unmatched else []))
                            or "no measurement matches a simulated response")
    try:
        result = calibrate({t.response: fits[t.response] for t in doe_targets}, doe_targets,
                           constraints=list(config.constraints), priors=[p.model_dump() for p in config.priors],
                           allow_extrapolation=config.allow_extrapolation, seed=config.seed)
    except DoeError as exc:
        raise AnalysisError(f"calibration failed: {exc}") from exc
    reach = {r["response"]: r for r in result.reachability}
    parameters = {name: result.parameters[name] for name in design.names}
    predictions, target_rows = {}, []
    for row in result.targets:
        name = row["response"]
        predictions[name] = {"value": row["predicted"], "pi_low": row["pi_low"], "pi_high": row["pi_high"],
                             "ci_low": row["ci_low"], "ci_high": row["ci_high"]}
        meas, u, assumed = by_response[name]
        target_rows.append({
            "measurement_id": meas.id, "response": name, "test": meas.test, "quantity": meas.quantity,
            "condition": dict(meas.condition), "measured": meas.mean, "uncertainty": u,
            "uncertainty_assumed": assumed, "predicted": row["predicted"], "pi_low": row["pi_low"],
            "pi_high": row["pi_high"], "standardised_residual": row["standardised_residual"],
            "reachability": reach[name]["min_standardised_misfit"], "reachable": reach[name]["reachable"],
        })
    optimum = {
        "parameters": parameters,
        "coded": {f.name: float(f.to_coded(parameters[f.name])) for f in design.factors},
        "parameter_std": {k: result.parameter_std.get(k) for k in design.names},
        "objective": result.objective, "success": result.success, "message": result.message,
        "predictions": predictions, "targets": target_rows,
        "active_bounds": result.active_bounds, "active_constraints": result.active_constraints,
        "constraints": result.constraints, "priors": result.priors,
        "reachability": [{k: v for k, v in r.items()} for r in result.reachability],
    }
    return {"models": models, "optimum": _json_safe(optimum)}


def confirmation_check(config, design_dict: dict, runs, targets, optimum: dict,
                       observed: dict[str, float]) -> dict[str, Any]:
    """doe.confirm verdict on the confirmation battery and, if it fails, the proposed next design."""
    from service.campaigns.design import design_view

    design = Design.from_dict(design_dict)
    _, fits, _ = fit_targets(design, runs, targets)
    observed = {k: v for k, v in observed.items() if k in fits and k in optimum["predictions"]}
    if not observed:
        return {"verdict": "not testable", "reason": "no modelled response in the confirmation run"}
    result = confirm({k: fits[k] for k in observed}, optimum["parameters"], observed,
                     seed=config.seed + 1)
    out = {"verdict": result.verdict, "confirmed": result.confirmed, "reason": result.reason,
           "next_design_kind": result.next_design_kind}
    if result.next_design is not None:
        view = design_view(result.next_design)
        view.pop("doe")
        out["next_design"] = view
    return _json_safe(out)


def _json_safe(value):
    """NaN/inf -> None and numpy scalars -> Python, so the JSON column stores plain data."""
    if isinstance(value, dict):
        return {str(k): _json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_json_safe(v) for v in value]
    if isinstance(value, (np.floating, float)):
        value = float(value)
        return value if math.isfinite(value) else None
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value
