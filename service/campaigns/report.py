"""Per-target model-vs-measurement report of one iteration.

For every target: measured (mean, standard uncertainty), predicted at the
optimum (with prediction interval), confirmed (the confirmation battery),
standardised residual of the confirmation, and reachability (the smallest
standardised misfit any parameter set in the design box can reach; > 3 means
the model, as parameterised, cannot reproduce the measurement).
"""
from __future__ import annotations

import math
from typing import Any

from service.campaigns.responses import find_response

REACHABLE_LIMIT = 3.0


def build_report(config, models: dict, optimum: dict, confirmation, targets, next_step: dict | None) -> dict[str, Any]:
    confirmed_responses = confirmation.responses or {}
    by_target = {t["measurement_id"]: t for t in optimum.get("targets", [])}
    rows = []
    for meas in targets:
        row: dict[str, Any] = {
            "measurement_id": meas.id, "test": meas.test, "quantity": meas.quantity,
            "condition": dict(meas.condition), "unit": meas.unit, "measured": meas.mean,
            "n": len(meas.values),
        }
        opt_target = by_target.get(meas.id)
        name = find_response(confirmed_responses, meas.test, meas.quantity, meas.condition)
        if name is None:
            row.update(status="not_simulated",
                       note="the battery produced no value for this test, quantity and condition")
            rows.append(row)
            continue
        confirmed = confirmed_responses[name]["value"]
        row.update(response=name, confirmed=confirmed)
        if opt_target is None:
            model = models.get(name) or {}
            row.update(status="not_modelled", note=model.get("error") or "no fitted model for this response")
            rows.append(row)
            continue
        u_meas = opt_target["uncertainty"]
        sim_sd = (models.get(name) or {}).get("pure_error_sd")
        u_total = math.sqrt(u_meas**2 + (sim_sd or 0.0) ** 2)
        pred = optimum["predictions"].get(name, {})
        lo, hi = pred.get("pi_low"), pred.get("pi_high")
        row.update(
            status="modelled",
            measured_uncertainty=u_meas,
            uncertainty_assumed=opt_target.get("uncertainty_assumed", False),
            predicted=pred.get("value"), prediction_interval=[lo, hi],
            predicted_standardised_residual=opt_target.get("standardised_residual"),
            simulator_sd=sim_sd,
            standardised_residual=(confirmed - meas.mean) / u_total if u_total > 0 else None,
            confirmation_in_interval=(lo is not None and hi is not None and lo <= confirmed <= hi),
            reachability=opt_target.get("reachability"),
            reachable=opt_target.get("reachable"),
        )
        rows.append(row)
    modelled = [r for r in rows if r["status"] == "modelled"]
    unreachable = [r for r in modelled if r.get("reachable") is False]
    outside = [r for r in modelled if not r["confirmation_in_interval"]]
    verdict = "calibrated"
    if unreachable:
        verdict = "targets out of reach"
    elif outside:
        verdict = "confirmation outside prediction interval"
    return {
        "optimum": optimum.get("parameters"),
        "fixed_parameters": dict(config.fixed_parameters),
        "confirmation_seed": confirmation.seed,
        "confirmation_job_id": confirmation.job_id,
        "targets": rows,
        "verdict": verdict,
        "unreachable": [r["response"] for r in unreachable],
        "confirmation_outside_interval": [r["response"] for r in outside],
        "max_abs_standardised_residual": max((abs(r["standardised_residual"]) for r in modelled
                                              if r["standardised_residual"] is not None), default=None),
        "next_step": next_step,
    }
