"""Per-target model-vs-measurement report of one iteration, with one verdict.

For every target: measured (mean, standard uncertainty), predicted at the optimum (with prediction
interval), confirmed (the mean of the confirmation batteries, one per seed), standardised residual of
that mean (the simulator's scatter divided by the number of seeds, as in the lack of fit), and
reachability (the smallest standardised misfit any parameter set in the design box can reach;
> 3 means the model, as parameterised, cannot reproduce the measurement). Then where the model
fails (calibration.localise: lack of fit against the noise floor, shares per test, trends with
stress), the conflicts (parameters pinned at a bound, priors pulled off), the surface check (the
confirmation against the fitted models' intervals, which checks the surrogate, not the physics),
and the verdict (calibration.verdict). Last, the plausibility warnings of the measurements it used
(engine.lab.plausibility): a unit slip stored with a warning at entry is named again in every report
built on it, where "out of reach" would otherwise be read as missing physics.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np

from calibration.keys import ResponseKey, find_response
from calibration.analysis import report_verdict
from calibration.records import Measured
from calibration.suspect import suspects as suspect_measurements
from engine.lab.plausibility import record_warnings

# a target counts as reached within this many standard deviations (doe.optimise.calibrate's reach_threshold)
REACH_THRESHOLD = 3.0

REACHABLE_LIMIT = 3.0


def build_report(config, models: dict, optimum: dict, confirmations: list, targets, assessment: dict,
                 model_reach: dict | None = None) -> dict[str, Any]:
    """``confirmations``: the runs at the final optimum, one per seed; ``targets``: the measurements;
    ``model_reach``: per response, the range of every battery the iteration ran (``calibration.suspect``:
    a measurement far outside it is named as suspect)."""
    confirmed_responses = confirmations[0].responses or {}
    m = len(confirmations)
    # the optimum's row of each target, found by the one measurement key (a notebook's targets have no ids)
    optimum_rows = [(ResponseKey.from_record(t), t) for t in optimum.get("targets", [])]
    sim_sd = assessment.get("simulator_sd") or {}
    # the surfaces' prediction intervals for the mean of the m confirmation batteries (doe.confirm)
    interval_of_mean = {r["response"]: (r["pi_low"], r["pi_high"])
                        for r in (assessment.get("surrogate_check") or {}).get("responses", [])}
    rows = []
    targets = [t if isinstance(t, Measured) else Measured.from_record(t) for t in targets]
    for meas in targets:
        key = meas.key
        row: dict[str, Any] = {
            "measurement_id": meas.id, "test": key.test, "quantity": key.quantity,
            "condition": key.condition_dict, "unit": meas.unit, "measured": meas.mean, "n": meas.n,
            "input_unit": meas.input_unit or None,
        }
        opt_target = next((t for k, t in optimum_rows if k.matches(key)), None)
        name = find_response(confirmed_responses, key)
        if name is None:
            row.update(status="not_simulated",
                       note="the battery produced no value for this test, quantity and condition")
            rows.append(row)
            continue
        per_seed = [(r.responses or {}).get(name, {}).get("value") for r in confirmations]
        confirmed = float(np.mean([v for v in per_seed if v is not None]))
        row.update(response=name, confirmed=confirmed, confirmed_per_seed=per_seed)
        if opt_target is None:
            model = models.get(name) or {}
            row.update(status="not_modelled", note=model.get("error") or "no fitted model for this response")
            rows.append(row)
            continue
        u_meas = opt_target["uncertainty"]
        sd = sim_sd.get(opt_target["response"])
        u_total = math.sqrt(u_meas**2 + (sd or 0.0) ** 2 / m)
        pred = optimum["predictions"].get(name, {})
        lo, hi = interval_of_mean.get(name, (pred.get("pi_low"), pred.get("pi_high")))
        row.update(
            status="modelled",
            measured_uncertainty=u_meas,
            uncertainty_assumed=opt_target.get("uncertainty_assumed", False),
            predicted=pred.get("value"), prediction_interval=[lo, hi],
            predicted_standardised_residual=opt_target.get("standardised_residual"),
            simulator_sd=sd, residual_sd=u_total,
            standardised_residual=(confirmed - meas.mean) / u_total if u_total > 0 else None,
            confirmation_in_interval=(lo is not None and hi is not None and lo <= confirmed <= hi),
            reachability=opt_target.get("reachability"),
            reachable=opt_target.get("reachable"),
        )
        surface = (models.get(name) or {}).get("fit") or {}
        # a surface on the runs that hold this response (doe.missing), or on ln(y) (doe.transform)
        notes = list(surface.get("reduction_log") or []) + (
            ["surface fitted to ln(y): Box-Cox rejected the plain scale"] if surface.get("transform") == "log" else [])
        if notes:
            row["note"] = "; ".join(notes)
        rows.append(row)
    modelled = [r for r in rows if r["status"] == "modelled"]
    if assessment.get("polished"):
        # the surfaces judged reach; once polishing has moved the optimum on the batteries themselves, a
        # battery there within the same standardised distance of the measurement has reached it, whatever
        # the surfaces said (reused batteries make surfaces that follow the box less closely at its edges)
        for r in modelled:
            z = r.get("standardised_residual")
            if r.get("reachable") is False and z is not None and abs(z) <= REACH_THRESHOLD:
                r.update(reachable=True, reached_by="the batteries at the polished optimum")
    unreachable = [r["response"] for r in modelled if r.get("reachable") is False]
    outside = [r["response"] for r in modelled if not r["confirmation_in_interval"]]
    loc = assessment.get("localisation")
    suspects = suspect_measurements(rows, model_reach or {})
    return {
        "optimum": optimum.get("parameters"),
        "fixed_parameters": dict(config.fixed_parameters),
        "confirmation_seed": confirmations[0].seed,
        "confirmation_job_id": confirmations[0].job_id,
        "confirmation_seeds": [r.seed for r in confirmations],
        "confirmation_job_ids": [r.job_id for r in confirmations],
        "targets": rows,
        **report_verdict(unreachable, assessment, suspects),
        "suspect_measurements": suspects,
        "unreachable": unreachable,
        "confirmation_outside_interval": outside,
        "max_abs_standardised_residual": max((abs(r["standardised_residual"]) for r in modelled
                                              if r["standardised_residual"] is not None), default=None),
        "lack_of_fit": loc["lack_of_fit"] if loc else None,
        "tests": loc["tests"] if loc else [],
        "trends": loc["trends"] if loc else {},
        "conflicts": loc["conflicts"] if loc else {"active_bounds": [], "priors_pulled": []},
        # conflicts or unreachable targets: the diagnosis runs (and its directed test) even if the lack of fit passes
        "suspect": bool(loc and loc.get("suspect")),
        "surrogate_check": assessment.get("surrogate_check"),
        # intervals on the free parameters with every noise term, widened by a failing fit; trades named
        "intervals": assessment.get("intervals"),
        "warnings": record_warnings(targets),
    }
