"""The loop's analysis, report and diagnosis computations on an iteration's runs.

The targets are measurements (``calibration.records.Measured``) matched to the batteries' responses
on the one (test, quantity, condition) key of ``calibration.keys``. Runs are any objects with
``std_order``, ``seed`` and ``responses`` (the service's rows or ``calibration.state``'s records);
the results are the plain JSON an iteration stores, whoever stores it (``calibration.machine``).
"""
from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Sequence

import numpy as np

from calibration import calibrate as cal
from calibration.attribute import signature_seeds
from calibration import fits
from calibration import polish, stats
from calibration.fitting import TargetModel
from calibration.localise import ALPHA, localise
from calibration.intervals import parameter_intervals, widen_to_measured
from calibration.records import Measured
from calibration.verdict import failing_tests, verdict
from calibration.vocabulary import DiagnosisVerdict
from doe.confirm import confirm
from doe.designs import Design
from doe.factors import DoeError


class AnalysisError(Exception):
    pass


def _measured(targets) -> list[Measured]:
    return [t if isinstance(t, Measured) else Measured.from_record(t) for t in targets]


def _runs(design: Design, runs) -> list[list[dict]]:
    by_std = sorted(runs, key=lambda r: r.std_order)
    if [r.std_order for r in by_std] != list(range(1, design.n_runs + 1)):
        raise AnalysisError("design runs do not match the stored design")
    return [list((r.responses or {}).values()) for r in by_std]


def fit(design_dict: dict, runs, targets) -> tuple[Design, list[TargetModel]]:
    """The iteration's design and its targets' response surfaces, fitted once per iteration: every
    phase after the design's batteries (analysis, polishing rounds, report, diagnosis) asks again and
    gets the same fit back (``calibration.fits``); after a restart the first ask refits it exactly."""
    return fits.fitted(design_dict, _runs(Design.from_dict(design_dict), runs), _measured(targets))


def _models_json(models: list[TargetModel]) -> dict[str, Any]:
    return {m.key.name: m.to_dict() for m in models if m.key is not None}


def analyse(config, design_dict: dict, runs, targets) -> dict[str, Any]:
    """Fit every matched target, then calibrate (doe.optimise through calibration.calibrate)."""
    design, models = fit(design_dict, runs, targets)
    modelled = [m for m in models if m.fit is not None]
    if not modelled:
        problems = [f"{m.key.name}: {m.error}" for m in models if m.key is not None]
        unmatched = [f"{m.target.key.test}/{m.target.key.quantity}" for m in models if m.key is None]
        raise AnalysisError("no target could be modelled: " + "; ".join(
            problems + ([f"not simulated: {', '.join(unmatched)}"] if unmatched else []))
            if problems or unmatched else "no target could be modelled: no measurement matches a simulated response")
    try:
        result = cal.optimum(models, default_relative=config.default_relative_uncertainty,
                             discrepancy=config.model_discrepancy,
                             priors=[p.model_dump() for p in config.priors], constraints=list(config.constraints),
                             seed=config.seed, allow_extrapolation=config.allow_extrapolation)
    except DoeError as exc:
        raise AnalysisError(f"calibration failed: {exc}") from exc
    reach = {r["response"]: r for r in result.reachability}
    parameters = {name: result.parameters[name] for name in design.names}
    predictions, target_rows = {}, []
    by_name = {m.key.name: m for m in modelled}
    variances = cal.target_variances([m.target for m in models], config.default_relative_uncertainty,
                                     config.model_discrepancy)
    for row in result.targets:
        name = row["response"]
        predictions[name] = {"value": row["predicted"], "pi_low": row["pi_low"], "pi_high": row["pi_high"],
                             "ci_low": row["ci_low"], "ci_high": row["ci_high"]}
        meas = by_name[name].target
        var = variances[meas.key]
        target_rows.append({
            "measurement_id": meas.id, "response": name, "test": meas.key.test, "quantity": meas.key.quantity,
            "condition": meas.key.condition_dict, "measured": meas.mean, "uncertainty": math.sqrt(var.variance),
            "uncertainty_assumed": var.source.startswith("assumed"),  # "assumed + model-form discrepancy" too "uncertainty_source": var.source,
            "predicted": row["predicted"], "pi_low": row["pi_low"],
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
        "reachability": [dict(r) for r in result.reachability],
    }
    return {"models": _json_safe(_models_json(models)), "optimum": _json_safe(optimum)}


def assess(config, design_dict: dict, runs, targets, optimum: dict, confirmation_records: list[list[dict]],
           confirmation_seeds: list[int], measured: Sequence[tuple[dict, list[list[dict]]]] = (),
           measured_seeds: list[int] | None = None) -> dict[str, Any]:
    """The report step, on one fit: the surface check (doe.confirm), the localisation of the
    confirmation batteries' mean (one record list per seed) against the measurements, and the one verdict.
    ``measured``: other points measured on batteries at ``measured_seeds`` (natural parameters, one record list
    per seed; ``polish.measured_points``), to which the intervals are widened where the data do not reject them.
    Where those seeds are not the confirmation's (a held-out confirmation, ``calibration.polish.hold_out``), the
    likelihood ratio is taken among the measured points alone, from the best of them: chi2 of one point at two
    sets of seeds differ by the packings' scatter, which is no evidence about the parameters."""
    design, models = fit(design_dict, runs, targets)
    modelled = [m for m in models if m.fit is not None]
    conf = cal.confirm(modelled, confirmation_records, confirmation_seeds)
    surrogate = _surrogate_check(config, modelled, optimum, conf)
    theta = dict(optimum["parameters"])
    localisation = None
    if surrogate["verdict"] != "not testable":  # a modelled response was confirmed
        residuals, localisation = _localised(config, design, modelled, optimum, conf)
        intervals = parameter_intervals(residuals, design, theta, localisation.lack_of_fit,
                                        discrepancy=config.model_discrepancy)
        seeds = list(measured_seeds or confirmation_seeds)
        points = _measured_chi2(config, design, modelled, measured, seeds, len(residuals.keys))
        best = residuals.chi2() if seeds == list(confirmation_seeds) or not points else min(c for _, c in points)
        intervals = widen_to_measured(intervals, design, theta, best, points)
    return _json_safe({"surrogate_check": surrogate,
                       "localisation": localisation.to_dict() if localisation is not None else None,
                       "intervals": intervals if localisation is not None else None,
                       "simulator_sd": {m.key.name: conf.sim_sd.get(m.key) for m in modelled}})


def _measured_chi2(config, design, modelled, measured, seeds, n_targets: int) -> list[tuple[dict, float]]:
    """(parameters, chi2 with the priors) of each measured point whose batteries gave every target the
    optimum's did: the same objective as ``polish``'s, so the two compare."""
    out = []
    for natural, point_records in measured:
        res = polish._residuals(config, design, modelled, dict(natural), point_records, seeds)
        if len(res.keys) == n_targets:
            out.append((dict(natural), res.chi2()))
    return out


def _surrogate_check(config, modelled, optimum: dict, conf) -> dict[str, Any]:
    """Do the fitted response surfaces predict the batteries at ``optimum["parameters"]`` (doe.confirm's
    prediction intervals, the confirmation's seeds averaged)? The report's ``surrogate_check``."""
    from calibration.design import design_view

    observed = {m.key.name: conf.mean[m.key] for m in modelled
                if m.key in conf.mean and m.key.name in optimum["predictions"]}
    if not observed:
        return {"verdict": "not testable", "reason": "no modelled response in the confirmation run"}
    result = confirm({m.key.name: m.fit for m in modelled if m.key.name in observed}, optimum["parameters"],
                     observed, seed=config.seed + 1, n_observations=len(conf.seeds))
    surrogate = {"verdict": result.verdict, "confirmed": result.confirmed, "reason": result.reason,
                 "next_design_kind": result.next_design_kind, "responses": result.responses,
                 "n_observations": len(conf.seeds),
                 "about": "the fitted response surfaces against the battery at the optimum; this checks the "
                          "surrogate, not the model against the measurements"}
    if result.next_design is not None:
        view = design_view(result.next_design)
        view.pop("doe")
        surrogate["next_design"] = view
    return surrogate


def surrogate_check(config, modelled, optimum: dict, confirmation_records: list[list[dict]],
                    confirmation_seeds: list[int]) -> dict[str, Any]:
    """The surfaces' check of ``assess`` on its own (``modelled``: the fitted targets of ``fit``): what
    ``polish_when="surrogate_misses"`` asks of the confirmation batteries before queueing a polishing round."""
    return _json_safe(_surrogate_check(config, modelled, optimum,
                                       cal.confirm(modelled, confirmation_records, confirmation_seeds)))


def confirmation_localisation(config, design, modelled, optimum: dict, confirmation_records: list[list[dict]],
                              confirmation_seeds: list[int]):
    """The report's localisation (``localise``: the lack of fit, the priors pulled off, the bounds) of the
    confirmation batteries at the surfaces' optimum, before any polishing: what ``polish_when=
    "surrogate_misses"`` also asks of an iteration that added an effect (None when nothing modelled was
    confirmed)."""
    conf = cal.confirm(modelled, confirmation_records, confirmation_seeds)
    if not conf.mean:
        return None
    return _localised(config, design, modelled, optimum, conf)[1]


def anchored_points(config, design, modelled, pulled: list[dict], optimum: dict,
                    confirmation_records: list[list[dict]], confirmation_seeds: list[int]) -> list[dict]:
    """Points of the missed measured parameters' profiles for the polish to try on the batteries
    (``calibration.polish``), each the surfaces' optimum with some parameters held at their measured values
    (clipped to their boxes) and the others free: each missed one (``pulled``: the localisation's
    ``priors_pulled`` rows) held alone, and, where more parameters were measured, the missed ones together with
    every measured parameter whose measurement is the better evidence for it (``calibrate.measurement_led``, at
    the optimum's confirmation batteries). Why both: held alone, the others move to make up on the surfaces for
    what it gave up, and on a biased surface they overshoot (tier B's hertz_strong, session 37: friction_pp held
    at 0.655 put friction_pw at 0.75 against its own tilt test's 0.56); held together they are the point the
    direct measurements define. Why not every measured one: a parameter a target fixes better than its own
    measurement, held at that measurement, spends the target's evidence (hertz_strong, session 40: the particle
    density held at a pycnometer reading 2 % high, 2,703 against 2,650 kg/m3, put the anchor's chi2 at 36.0, above
    the optimum's 28.4, the fill's bulk density missed by several of its sd).
    Each as {"held": {name: value}, "parameters": {...}}; a point the constraints or the box do not allow is
    left out, and one already listed is not repeated."""
    def held_value(name: str, value: float) -> float:
        f = design.factor(name)
        return min(max(float(value), f.low), f.high)

    measured = {p.parameter: held_value(p.parameter, p.value) for p in config.priors if p.parameter in design.names}
    sets = [{row["parameter"]: measured[row["parameter"]]} for row in pulled if row["parameter"] in measured]
    if sets and len(measured) > 1:
        conf = cal.confirm(modelled, confirmation_records, confirmation_seeds)
        res = cal.residuals_at(design, modelled, dict(optimum["parameters"]), conf,
                               [p.model_dump() for p in config.priors], config.default_relative_uncertainty,
                               config.model_discrepancy)
        led = set(cal.measurement_led(res)) | {name for held in sets for name in held}
        sets.append({name: value for name, value in measured.items() if name in led})
    out = []
    for held in sets:
        if any(point["held"] == held for point in out) or len(held) == len(design.names):
            continue
        try:
            result = cal.optimum(modelled, default_relative=config.default_relative_uncertainty,
                                 discrepancy=config.model_discrepancy, priors=[p.model_dump() for p in config.priors],
                                 constraints=list(config.constraints), fixed=held, seed=config.seed,
                                 allow_extrapolation=config.allow_extrapolation)
        except DoeError:
            continue
        if result.success:
            out.append({"held": held, "parameters": {n: float(result.parameters[n]) for n in design.names}})
    return out


def _localised(config, design, modelled, optimum: dict, conf):
    """(residuals, localisation) of the confirmation ``conf`` at the optimum: the one noise model and the
    one localisation every judgement of the batteries there uses."""
    theta = dict(optimum["parameters"])
    priors = [p.model_dump() for p in config.priors]
    res = cal.residuals_at(design, modelled, theta, conf, priors, config.default_relative_uncertainty,
                           config.model_discrepancy)
    # the polish's held-out confirmation (calibration.polish.hold_out): judged on what no parameter absorbs
    held = set((optimum.get("polish") or {}).get("holdout_seeds") or [])
    if held and held.issuperset(conf.seeds):
        res = replace(res, held_out=True)
    loc = localise(res, active_bounds=cal.active_bounds(design, theta), priors=cal.prior_rows(priors, theta),
                   reachability=optimum.get("reachability", []), seed=config.seed)
    return res, loc


def diagnosis_projection(res, design, theta: dict[str, float], priors=()):
    """M for the diagnosis: what the free parameters cannot absorb, where a parameter pinned on a box edge
    short of its typical range counts as absorbing.

    The report's lack of fit judges the model in its box, so a parameter pinned with the misfit pushing
    outward absorbs nothing more there (``calibrate.residuals_at``). The diagnosis asks another question:
    which physics is missing. A friction coefficient at 1.0 cannot go further (the misfit it leaves is the
    candidates' to explain); a contact stiffness at a box edge of 3 MN/m can, and the automatic mode gives it
    the room (``decisions.widened_box``). A signature along what the wider box would absorb is no evidence
    of missing physics: the founding case's E' deficit with the stiffness pinned is not Hertz-Mindlin's.
    Returns (M, the names of the parameters counted as absorbing for that reason only)."""
    from calibration.decisions import widened_box

    pinned = {b["parameter"]: b["side"] for b in cal.active_bounds(design, theta)}
    measured = {p.parameter: p for p in priors}
    absorbing, room = [], []
    for keep, name in zip(res.absorbing, res.free):
        f = design.factor(name)
        wider = not keep and pinned.get(name) is not None and widened_box(
            {"name": name, "low": f.low, "high": f.high, "log": f.log}, pinned[name], prior=measured.get(name)) is not None
        absorbing.append(bool(keep or wider))
        if wider:
            room.append(name)
    return replace(res, absorbing=absorbing).M(), room


def active_effects(iteration_parameters: dict) -> set[str]:
    """Names of the effects already in an iteration's model (``iteration_parameters``: its factors, fixed
    parameters and fixed contact effects): every fixed contact effect, and every candidate that says it
    is active there (``Candidate.active_in``: its strength a factor, or fixed away from "off")."""
    from engine.candidates import candidates

    factors = iteration_parameters.get("factors") or []
    fixed = {**(iteration_parameters.get("fixed") or {}), "effects": iteration_parameters.get("effects") or {}}
    active = set(fixed["effects"])
    active |= {name for name, c in candidates().items() if c.active_in(factors, fixed)}
    return active


def candidate_points(config, optimum: dict, iteration_parameters: dict) -> list[tuple[str, dict[str, float]]]:
    """(candidate, factor values) of the diagnosis batteries: the optimum with each candidate not yet
    in the model switched on at its secant step (a switch-type effect at its matched strength)."""
    from calibration import parameters as factor_paths
    from engine.candidates import candidates
    from engine.lab.spec import MicroParameters

    active = active_effects(iteration_parameters)
    out = []
    for name, c in candidates().items():
        if name in active or not c.applies_to(config.fidelity):
            continue
        values = dict(optimum["parameters"])
        if c.is_switch:
            full = factor_paths.apply(config.fixed_parameters, values)
            values[c.factor] = float(c.reference(MicroParameters.model_validate(full)))
        else:
            values[c.factor] = (c.off_value or 0.0) + c.step
        out.append((name, values))
    return out


BASELINE = "baseline"


def diagnosis_plan(config, optimum: dict, iteration_parameters: dict, confirmation_seeds: list[int]) -> list[tuple]:
    """(name, factor values, seed) of every diagnosis battery, in a fixed order: a baseline battery at
    the optimum, then each candidate, at as many seeds as the confirmation has, but seeds of their own
    (calibration.attribute.signature_seeds: a signature measured against the confirmation batteries
    would share their noise with the residuals)."""
    seeds = signature_seeds(confirmation_seeds)
    plan = [(BASELINE, dict(optimum["parameters"]), seed) for seed in seeds]
    for name, values in candidate_points(config, optimum, iteration_parameters):
        plan += [(name, values, seed) for seed in seeds]
    return plan


def top_probe_plan(config, optimum: dict, names: list[str], confirmation_seeds: list[int]) -> list[tuple]:
    """(name, factor values, seed) of the second probe of each of ``names`` (``attribute.top_probes``): the
    optimum with the candidate at its plausible top (``Candidate.top_step`` from "off"), at the diagnosis seeds
    of ``confirmation_seeds``, so each pairs with the baseline battery already run at the same seed."""
    from engine.candidates import candidates

    table = candidates()
    plan = []
    for name in names:
        c = table[name]
        values = {**dict(optimum["parameters"]), c.factor: (c.off_value or 0.0) + c.top_step}
        plan += [(name, values, seed) for seed in signature_seeds(confirmation_seeds)]
    return plan


def diagnose(config, design_dict: dict, runs, targets, optimum: dict, confirmation_records: list[list[dict]],
             confirmation_seeds: list[int], planned: list[tuple]) -> dict[str, Any]:
    """Rank the candidate effects (calibration.attribute) from their batteries at the optimum.

    ``planned``: (name, seed, records, probe) of the diagnosis batteries (``diagnosis_plan`` order, then any
    ``top_probe_plan``; probe ``attribute.STEP`` or ``attribute.TOP``, STEP when left out). The residuals are
    the report's (the confirmation batteries); each probe's signature is its mean minus the planned baseline's
    at the same seeds (common random numbers), seeds the confirmation did not use, so that the signatures'
    noise is independent of the residuals."""
    from calibration.attribute import STEP, TOP, Signature, attribute, signature_noise_var, signature_vector
    from calibration.fitting import run_values
    from engine.candidates import candidates

    design, models = fit(design_dict, runs, targets)
    modelled = [m for m in models if m.fit is not None]
    conf = cal.confirm(modelled, list(confirmation_records), list(confirmation_seeds))
    res, loc = _localised(config, design, modelled, optimum, conf)
    table = candidates()
    signatures = []
    planned = [(entry[0], entry[1], entry[2], entry[3] if len(entry) > 3 else STEP) for entry in planned]
    baseline = {seed: run_values(records) for n, seed, records, _ in planned if n == BASELINE}
    for name, probe in dict.fromkeys((n, pr) for n, _, _, pr in planned if n != BASELINE):
        c = table[name]
        batteries = [(seed, run_values(records)) for n, seed, records, pr in planned if n == name and pr == probe]
        values = [v for _, v in batteries]
        step = 1.0 if c.is_switch else (c.top_step if probe == TOP else c.step)
        vector = signature_vector(res, values, [baseline[seed] for seed, _ in batteries], step)
        noise = signature_noise_var(res, conf.sim_sd, len(values), step)
        reference = None
        if c.is_switch:
            reference = next((v[c.factor] for n, v in candidate_points(config, optimum, {}) if n == name), None)
        signatures.append(Signature(c, vector, step, reference, noise, probe))
    M, room = diagnosis_projection(res, design, dict(optimum["parameters"]), config.priors)
    left = stats.lack_of_fit(res.judged, M, res.df, seed=config.seed) if room else None
    att = attribute(loc, res.r, M, signatures, [k.label for k in res.keys],
                    room=(room, left.p_value if left is not None else 0.0))
    from calibration.replicates import simulator_share

    share = simulator_share({k: conf.sim_sd[k] for k in res.keys if k in conf.sim_sd},
                            {k: float(res.sd[i]) for i, k in enumerate(res.keys)})
    return _json_safe({**att.to_dict(), "lack_of_fit": loc.lack_of_fit.to_dict(), "simulator_share": share,
                       "seeds": sorted(set(confirmation_seeds) | {s for _, s, _, _ in planned}),
                       "batteries": len(planned)})


def model_fails(report: dict) -> bool:
    """Does the model miss the measurements? The diagnosis's adequacy test (the omnibus lack of fit and
    the candidates' directed test, Holm) once it has run, else the report's omnibus lack of fit."""
    adequacy = report.get("adequacy")
    if adequacy is not None:
        return bool(adequacy["fails"])
    p = (report.get("lack_of_fit") or {}).get("p_value")
    return p is not None and p < ALPHA


def diagnosed_report(report: dict, diagnosis: dict, suspects: list[dict] | None = None) -> dict[str, Any]:
    """The report with its diagnosis, and its verdict judged again on the diagnosis's adequacy test,
    which has seen the candidates' batteries: a misfit only the directed test finds makes "calibrated"
    "model misses the measurements". ``suspects``: the suspect measurements judged again with the
    candidates' batteries (``calibration.suspect``; None keeps the report's); where one remains, the
    diagnosis says so instead of naming an effect, and indicates none."""
    suspects = report.get("suspect_measurements") or [] if suspects is None else suspects
    if suspects:
        diagnosis = {**diagnosis, "attribution_verdict": diagnosis["verdict"],
                     "verdict": DiagnosisVerdict.SUSPECT_MEASUREMENT.value,
                     "message": "; ".join(s["message"] for s in suspects) + ": no candidate effect at a plausible "
                                "strength moves the model there, so check the measurement before adding physics",
                     "indicated": [], "measure_next": [f"{s['test']} {s['quantity']}" for s in suspects]}
    out = {**report, "diagnosis": diagnosis, "suspect_measurements": suspects,
           "adequacy": {**diagnosis["adequacy"], "omnibus_p": diagnosis["lack_of_fit"]["p_value"],
                        "directed": diagnosis.get("directed")}}
    surrogate = report.get("surrogate_check") or {}
    polished = bool((report.get("polish") or {}).get("steps"))
    out.update(verdict(unreachable=report.get("unreachable") or [], lack_of_fit_fails=out["adequacy"]["fails"],
                       surrogate_ok=None if polished else surrogate.get("confirmed"),
                       failing_tests=failing_tests(report.get("tests")), suspects=suspects,
                       lack_of_fit=report.get("lack_of_fit"), adequacy_p=out["adequacy"].get("p_value")))
    return out


def report_verdict(unreachable: list, assessment: dict, suspects: list[dict] = ()) -> dict[str, Any]:
    """One verdict. Once polishing has moved the optimum on the batteries themselves, the surfaces no
    longer decide where the optimum is, so their check is reported but does not veto "calibrated"."""
    loc = assessment.get("localisation")
    surrogate = assessment.get("surrogate_check") or {}
    # no degrees of freedom left: the adequacy test was not made (its p is NaN), so it neither fails nor passes
    testable = loc is not None and (loc["lack_of_fit"].get("dof") or 0) > 0
    return verdict(unreachable=unreachable, lack_of_fit_fails=loc["fails"] if testable else None,
                   surrogate_ok=None if assessment.get("polished") else surrogate.get("confirmed"),
                   failing_tests=failing_tests(loc["tests"] if loc else []), suspects=list(suspects),
                   lack_of_fit=loc["lack_of_fit"] if loc else None)


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
