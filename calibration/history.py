"""The error history of a loop: per iteration its model, optimum, weighted error against the noise
band, verdict and what the automatic mode decided; per target its residual in each iteration.

One function for the API, the page and a notebook's ``LoopResult.history()``: watching the error fall
as effects are added is the point of the loop, so it is computed in one place from what the
iterations stored.
"""
from __future__ import annotations

from typing import Any, Sequence

from calibration.analysis import active_effects
from calibration.decisions import explanation
from calibration.stats import weighted_rms


def history(iterations: Sequence[Any]) -> dict[str, Any]:
    """``{"iterations": [...], "targets": {...}}`` of the iterations that have a report."""
    done = [it for it in sorted(iterations, key=lambda i: i.number) if it.report]
    entries, previous, targets, plan, last = [], set(), {}, {}, None
    for it in done:
        report = it.report
        effects = sorted(active_effects(it.parameters))
        # in automatic mode an iteration is built on a named base (the one before, or an earlier one when
        # an added effect was rejected or its range widened): what it added is relative to that base
        base = next((b for b in done if b.number == plan.get("next_base")), None)
        if base is not None:
            previous = set(active_effects(base.parameters))
        else:
            base = last
        added = sorted(set(effects) - previous) or None
        lof = report.get("lack_of_fit") or {}
        diag = report.get("diagnosis")
        entries.append({
            "number": it.number, "effects": effects, "added_effect": added,
            "optimum": report.get("optimum"), "parameter_std": (it.optimum or {}).get("parameter_std"),
            # what the data fix: the report's 95 % interval (noise, simulator, misfit; cut at the box)
            "parameter_interval": _intervals(report),
            "chi2": lof.get("statistic"), "chi2_per_dof": lof.get("chi2_per_dof"), "dof": lof.get("dof"),
            "noise_band": lof.get("noise_band"), "lack_of_fit_p": lof.get("p_value"),
            # once the diagnosis ran: Holm over the lack of fit and the candidates' directed test
            "adequacy_p": (report.get("adequacy") or {}).get("p_value"),
            "directed_p": ((report.get("adequacy") or {}).get("directed") or {}).get("p_value"),
            "per_test": {t["test"]: t["chi2"] for t in report.get("tests", [])},
            # the weighted error the acceptance criteria halve: RMS of the targets' standardised residuals
            "weighted_rms": _finite(weighted_rms([row.get("standardised_residual") for row in report.get("targets", [])
                                                  if row.get("status") == "modelled"])),
            "verdict": report.get("verdict"),
            "top_effect": (diag or {}).get("ranking", [{}])[0].get("effect") if diag and diag.get("ranking") else None,
            # automatic mode: whether this iteration's added effect was kept, and why the loop stopped
            "decision": (report.get("automatic") or {}).get("decision"),
            "stop_reason": (report.get("automatic") or {}).get("stop_reason"),
            # a completed loop taken up again from here (machine.extended): the limit raised and what it had stopped for
            "continued": (report.get("automatic") or {}).get("continued"),
            "tie_break": ((report.get("automatic") or {}).get("tie_break") or {}).get("message"),
            # an alias fitted in place of an effect that passed, compared with it: the iteration kept, and the
            # two effects when the measurements could not tell them apart
            "kept_iteration": (report.get("automatic") or {}).get("kept_iteration"),
            "undistinguished": ((report.get("automatic") or {}).get("alias_settled") or {}).get("undistinguished"),
            "range_widened": bool(plan.get("widened")),
            # base factors whose box this iteration ran wider than the one it was built on (automatic mode)
            "box_widened": [w["parameter"] for w in plan.get("widened_box") or []],
            # an added effect explains the misfit only when every check holds; else what it leaves
            "explains": _explains(added, base, report),
            "batteries": batteries(it),
        })
        plan = report.get("automatic") or {}
        last = it
        previous = set(effects)
        for row in report.get("targets", []):
            if row.get("status") != "modelled":
                continue
            label = row.get("response") or row["quantity"]
            targets.setdefault(label, {"test": row["test"], "quantity": row["quantity"],
                                       "condition": row["condition"], "residuals": {}})
            targets[label]["residuals"][str(it.number)] = row.get("standardised_residual")
    for a, b in zip(entries, entries[1:]):
        a["effect_added_next"] = b["added_effect"]
    if entries:
        entries[-1]["effect_added_next"] = None
    return {"iterations": entries, "targets": targets}


def batteries(it) -> dict[str, Any]:
    """The batteries an iteration ran, per phase, the design rows it reused instead, and why each phase
    ran as many as it did (calibration.reuse, calibration.replicates, calibration.polish)."""
    from calibration.vocabulary import PolishJacobian, RunKind

    counts = {kind.value: 0 for kind in RunKind}
    reused = 0
    for run in it.runs:
        if getattr(run, "reused_from", None):
            reused += 1
        else:
            counts[str(getattr(run.kind, "value", run.kind))] += 1
    why = []
    design = it.design or {}
    if reused:
        why.append(f"{RunKind.DESIGN.value}: {(design.get('batteries') or {}).get('run', counts['design'])} run, "
                   f"{reused} reused from earlier iterations")
    why += [f"{RunKind.DIAGNOSIS.value}: {stage['why']}" for stage in (it.report or {}).get("diagnosis_stages") or []]
    polish = (it.optimum or {}).get("polish") or {}
    if polish.get("skipped"):
        why.append(f"{RunKind.POLISH.value}: skipped ({polish['skipped']})")
    elif polish:
        why.append(f"{RunKind.POLISH.value}: {polish.get('steps', 0)} step(s), Jacobian from the "
                   f"{polish.get('jacobian', PolishJacobian.BATTERIES.value)}"
                   + (f" ({polish['why']})" if polish.get("why") else ""))
    return {**counts, "reused": reused, "total": sum(counts.values()), "why": why}


def _explains(added: list[str] | None, base, report: dict) -> dict | None:
    """The automatic mode's word on the effect this iteration added, or for one added by hand the same
    rule with "kept" meaning that chi2 fell (``calibration.decisions.explanation``)."""
    if not added or base is None:
        return None
    decision = (report.get("automatic") or {}).get("decision")
    if decision and "explains" in decision:
        return {k: decision[k] for k in ("explains", "remaining", "explains_message")}
    before, after = (base.report or {}).get("lack_of_fit") or {}, report.get("lack_of_fit") or {}
    fell = before.get("statistic") is not None and after.get("statistic") is not None and \
        after["statistic"] < before["statistic"]
    return explanation(added, fell, base.report or {}, report)


def _intervals(report: dict) -> dict[str, list[float]] | None:
    """{parameter: [low, high]} of the report's intervals (``calibration.intervals``), or None before
    an iteration has them. The optimiser's sd (``parameter_std``) knows the targets' uncertainty alone
    and no box; a chart drawing optimum +- 2 of it put bars beyond the design box that the report's own
    intervals, cut there, never reach."""
    rows = ((report.get("intervals") or {}).get("parameters")) or {}
    out = {name: [float(row["low"]), float(row["high"])] for name, row in rows.items()
           if row.get("low") is not None and row.get("high") is not None}
    return out or None


def _finite(value: float) -> float | None:
    return value if value == value else None  # NaN (no modelled target) -> null
