"""Automatic mode: after each iteration, take the step a user would take next.

localise -> attribute -> add -> confirm, until the lack of fit passes, nothing improves, or the
campaign's ``max_iterations`` is reached; the reason it stopped is stored with the last iteration
(``report.automatic.stop_reason``) and shown in the campaign's summary and history.

An iteration that added an effect is judged against the iteration it was built on
(``calibration.decisions.judge``: the error must fall significantly, and a lack of fit that passed must still pass).
A rejected effect leaves the model as it was: the next candidate indicated by that earlier
iteration's diagnosis is tried instead, and when none is left nothing improves. An added strength
pinned at the top of its range (the optimum wants more than the range allows) is first given a range twice as wide on the same base, once (``calibration.decisions.widened_top``,
as the library loop does), and that iteration is the one judged. An effect that brings the fit into the noise
but shares an alias group with candidates never fitted has its first such partner fitted in its place on the
same base (``alias_refit``) before the loop stops, and the two fits are compared (``settle_alias``: the leader
stays unless the partner fits clearly better against noisy probes; fits the measurements cannot tell apart are
reported as undistinguished). A base factor pinned on a box edge short
of its typical range gets the box's width more on that side, once (``box_widening``): beside the next
effect, or alone when the diagnosis indicates none (it counted such a factor as absorbing). Pure functions of
what the database holds, so the runner stays resumable.
"""
from __future__ import annotations

from typing import Any, Callable

from calibration.adding import effect_hints, with_effect_factor
from calibration.analysis import active_effects, model_fails
from calibration.decisions import explanation, judge, widened_box, widened_top
from calibration.errors import SettingsError
from calibration.keys import ResponseKey
from calibration.settings import validated
from calibration.vocabulary import AGAINST_ADDING, DiagnosisVerdict, StopReason, Verdict
from engine.candidates import get as get_candidate

# validates the next iteration's settings (a JSON dict) and returns them as stored; raises with the reason
Validate = Callable[[dict], dict]


def _record(it) -> dict[str, Any]:
    return dict(((it.report or {}).get("automatic")) or {})


def _lof(report: dict) -> dict:
    return report.get("lack_of_fit") or {}


def judge_iteration(iterations: list, it, report: dict) -> tuple[dict | None, int | None]:
    """(decision, base iteration number) when ``it`` added an effect in automatic mode, else (None, None)."""
    previous = next((p for p in iterations if p.number == it.number - 1), None)
    plan = _record(previous) if previous is not None else {}
    name, base_number = plan.get("next_effect"), plan.get("next_base")
    if not name or base_number is None:
        return None, None
    base = next(p for p in iterations if p.number == base_number)
    before, after = _lof(base.report or {}), _lof(report)
    if not before.get("dof") or not after.get("dof"):
        return None, base_number
    c = get_candidate(name)
    n = int(before.get("n_residuals") or 0)
    decision = judge(c, chi2_before=before["statistic"], chi2_after=after["statistic"], n_residuals=n,
                     free_before=n - int(before["dof"]), free_after=n - int(after["dof"]),
                     lof_p_before=before["p_value"], lof_p_after=after["p_value"],
                     strength=((report.get("optimum") or {}).get(c.factor)), turned_off=turned_off(c, it, report))
    # kept or not, say how much of the misfit it explains: an effect kept with the fit still outside the
    # noise "partly explains" it, with what remains, and is not presented as the answer
    return {**decision.to_dict(), **explanation([name], decision.accepted, base.report or {}, report,
                                                decision.turned_off)}, base_number


def turned_off(candidate, it, report: dict) -> bool:
    """Does iteration ``it``'s optimum put ``candidate``'s strength on the low edge of its factor where that
    edge is the effect's "off" value (the report's active bounds)? A switch-type effect has no off strength."""
    if candidate.is_switch or candidate.off_value is None:
        return False
    factor = next((f for f in (it.parameters or {}).get("factors", []) if f["name"] == candidate.factor), None)
    if factor is None or abs(float(factor["low"]) - float(candidate.off_value)) > 1e-12 * max(1.0, abs(factor["high"])):
        return False
    return any(b.get("parameter") == candidate.factor and b.get("side") == "low"
               for b in (report.get("conflicts") or {}).get("active_bounds", []))


def widening(config, iterations: list, it, report: dict) -> dict | None:
    """{"effect", "factor", "base", "high"} when ``it`` added an effect in automatic mode whose strength the
    optimum pins at the top of its range and that range was not widened already (and another
    iteration is allowed); else None."""
    if it.number >= config.max_iterations:
        return None
    previous = next((p for p in iterations if p.number == it.number - 1), None)
    plan = _record(previous) if previous is not None else {}
    name = plan.get("next_effect")
    if not name or plan.get("widened"):
        return None
    c = get_candidate(name)
    pinned = any(b.get("parameter") == c.factor and b.get("side") == "high"
                 for b in (report.get("conflicts") or {}).get("active_bounds", []))
    factor = next((f for f in it.parameters.get("factors", []) if f["name"] == c.factor), None)
    top = widened_top(c, factor["high"]) if pinned and factor else None
    return None if top is None else {"effect": name, "factor": c.factor, "base": plan.get("next_base"), "high": top}


def box_widening(iterations: list, it, report: dict, priors=()) -> tuple[list[dict], list[dict]]:
    """(the factors of ``it`` with every base factor its optimum pins at a box edge moved out, the
    widenings as {"parameter", "side", "from", "to"}) by ``calibration.decisions.widened_box``; no
    widening leaves the factors as they were. An effect's strength is left to ``widening``; ``priors``
    (the settings' directly measured parameters) keep a measured parameter's box."""
    measured = {p.parameter: p for p in priors}
    first = next((p for p in iterations if p.number == 1), None)
    first_box = {f["name"]: f for f in ((first.parameters if first is not None else {}) or {}).get("factors", [])}
    pinned = {b.get("parameter"): b.get("side") for b in (report.get("conflicts") or {}).get("active_bounds", [])}
    factors, done = [], []
    for f in it.parameters.get("factors", []):
        side = pinned.get(f["name"])
        wider = widened_box(f, side, first_box.get(f["name"]), measured.get(f["name"])) if side in ("low", "high") \
            else None
        if wider is None:
            factors.append(dict(f))
            continue
        factors.append(wider)
        done.append({"parameter": f["name"], "side": side, "from": float(f[side]), "to": float(wider[side])})
    return factors, done


def builds_on(config, iterations: list, it, report: dict) -> bool:
    """Will the automatic mode build on iteration ``it``? Not when the effect it added did not earn its
    place (the next candidate then comes from the diagnosis of the iteration it was built on), nor when
    that effect's strength is pinned at the top of its range (the iteration is redone on a wider one), nor
    when it fits an alias in place of an effect that already passed (the loop stops after comparing the two):
    such an iteration needs no diagnosis of its own."""
    decision, _ = judge_iteration(iterations, it, report)
    rejected = decision is not None and not decision["accepted"]
    refit = refit_plan(iterations, it) is not None
    return not rejected and not refit and widening(config, iterations, it, report) is None


def kept_alias(iterations: list, decision: dict | None, base_number: int | None) -> dict | None:
    """{"effect", "aliases", "base", "separating", "message"} when the effect just kept shared an alias group
    in its base iteration's diagnosis with candidates never fitted in its place, else None.

    Why: an alias group says the measurements move alike under its members (tier B shape_strong: rolling
    resistance 0.13 and elongation 1.7 explain the same residual shear and dilatancy, cos 0.91). The loop adds
    the leader, and when it brings the fit into the noise it stops; the fit is then evidence that the model
    with that effect is adequate, not that the effect is the one missing, and a stop reason that says only
    "lack of fit passes" would present a stand-in as the answer. The message names the members not fitted and
    the measurement that would separate them."""
    if not decision or not decision.get("accepted") or base_number is None:
        return None
    base = next((p for p in iterations if p.number == base_number), None)
    diagnosis = ((base.report or {}).get("diagnosis") or {}) if base is not None else {}
    name = decision.get("effect")
    group = next((g for g in diagnosis.get("alias_groups") or [] if name in g.get("effects", [])), None)
    if group is None:
        return None
    fitted = _tried_from(iterations, base_number) | active_effects(base.parameters)
    others = [e for e in group["effects"] if e != name and e not in fitted]
    if not others:
        return None
    separating = _separating(group, {name})
    message = (f"{name} was kept, but iteration {base_number}'s diagnosis found it aliased with "
               f"{', '.join(others)}: these measurements change alike under them, so the fit does not say which is "
               f"missing; fit {', '.join(others)} in its place"
               + (f", or measure {' / '.join(separating)} more precisely, to tell them apart" if separating else
                  " to tell them apart"))
    return {"effect": name, "aliases": others, "base": base_number, "separating": separating, "message": message}


# two fits with as many free parameters each whose chi2 differ by less than this are not told apart by the
# measurements: the likelihood ratio is below e (Burnham & Anderson 2002, sec. 2.6: models within 2 of the best
# AIC keep substantial support)
UNDISTINGUISHED_CHI2 = 2.0


def refit_plan(iterations: list, it) -> dict | None:
    """The ``alias_refit`` plan iteration ``it`` carries out (the previous iteration's record), else None."""
    previous = next((p for p in iterations if p.number == it.number - 1), None)
    return _record(previous).get("alias_refit") if previous is not None else None


def alias_refit(config, campaign_config: dict, iterations: list, it, alias: dict,
                validate: Validate) -> dict[str, Any] | None:
    """The record that fits ``alias``'s first unfitted partner (in the base diagnosis's ranking order) on the
    base model, in place of the effect iteration ``it`` kept; None when no further iteration is allowed or the
    partner's iteration cannot be configured (the stop reason then keeps ``kept_alias``'s advice).

    Why: when the leader of an alias group brings the fit into the noise, the fit says the model with it is
    adequate, not that it is the effect missing (tier B shape_strong: rolling resistance kept where elongation
    was hidden, cos 0.91 between their signatures). Fitting the partner on the same base costs one iteration
    and answers the question the diagnosis could not: which of the two fits the measurements better."""
    if it.number >= config.max_iterations:
        return None
    base = next(p for p in iterations if p.number == alias["base"])
    base_report = base.report or {}
    order = [row.get("effect") for row in (base_report.get("diagnosis") or {}).get("ranking") or []]
    partner = sorted(alias["aliases"], key=lambda e: order.index(e) if e in order else len(order))[0]
    factors, _ = box_widening(iterations, base, base_report, config.priors)
    base_config = {**campaign_config, "factors": factors, "fixed_parameters": _fixed(base.parameters)}
    try:
        nxt = with_effect_factor(base_config, partner, **effect_hints(base_report, partner))
    except ValueError:  # SettingsError included: the partner cannot run on this base
        return None
    plan = {"leader": alias["effect"], "leader_iteration": it.number, "partner": partner, "base": alias["base"],
            "message": (f"{alias['effect']} brings the fit into the noise, but iteration {alias['base']}'s diagnosis "
                        f"found it aliased with {partner}: {partner} is fitted in its place on iteration "
                        f"{alias['base']}'s model, and the two fits are compared")}
    record = _configured({"alias_refit": plan}, partner, alias["base"], nxt, validate)
    return None if record.get("stop_reason") else record


def common_chi2(report_a: dict, report_b: dict) -> tuple[float | None, float | None]:
    """Two iterations' chi2 over the measured targets with one variance per target for both: the measurement's
    plus the simulator's scatter of a mean over the confirmation seeds, pooled over the two iterations.

    Why not each report's own lack-of-fit statistic: each divides by its own simulator sd, estimated from a few
    batteries, so a fit could look better only because its noise came out larger. The common variance makes the
    difference a difference of squared misfits (with the partner confirming at the leader's seeds, mostly of the
    models, not of the packings). Targets either report lacks are left out of both; with
    none in common, each report's lack-of-fit statistic is returned."""
    def rows(report: dict) -> dict:
        return {ResponseKey.from_record(r): r for r in report.get("targets") or [] if r.get("status") == "modelled"
                and r.get("confirmed") is not None and r.get("measured_uncertainty") is not None}

    a, b = rows(report_a), rows(report_b)
    seeds = max(1, min(len(report_a.get("confirmation_seeds") or [1]), len(report_b.get("confirmation_seeds") or [1])))
    common = [k for k in a if k in b]
    if not common:
        return _lof(report_a).get("statistic"), _lof(report_b).get("statistic")
    chi2_a = chi2_b = 0.0
    for k in common:
        sim_var = 0.5 * ((a[k].get("simulator_sd") or 0.0) ** 2 + (b[k].get("simulator_sd") or 0.0) ** 2) / seeds
        var = a[k]["measured_uncertainty"] ** 2 + sim_var
        if var <= 0:
            continue
        chi2_a += (a[k]["confirmed"] - a[k]["measured"]) ** 2 / var
        chi2_b += (b[k]["confirmed"] - b[k]["measured"]) ** 2 / var
    return chi2_a, chi2_b


def settle_alias(iterations: list, it, report: dict, decision: dict | None, plan: dict) -> dict[str, Any]:
    """{"leader", "partner", "kept_iteration", "kept_effect", "undistinguished", "chi2", "message"} once iteration
    ``it`` has fitted ``plan``'s partner in place of its leader, by their chi2 on one variance (``common_chi2``):

    * the partner did not earn its place, or its fit fails: the leader is kept;
    * the partner fits worse by ``UNDISTINGUISHED_CHI2`` or more: the leader is kept, the fits agreeing with the
      diagnosis's order;
    * within ``UNDISTINGUISHED_CHI2``: undistinguished, the leader shown, with the measurement that would decide;
    * the partner fits better by more: it is kept when the diagnosis's order rested on noisy probes (either
      signature's noise share, ``calibration.attribute.noise_share``, at least ``SIMULATOR_SHARE_MIN``), where
      the fits are the better evidence; otherwise the two pieces of evidence disagree, and it is undistinguished.

    Why the diagnosis may outvote the fit: the two fits come from response surfaces, a confirmation and a polish,
    each with its own error, and on the stand-in's test bed (probe noise about 1 %) a partner fitting better by
    more than 2 was the truth in 2 of 6 refits, the leader in 4 (tier A, session 26); on DEM the probes' own
    scatter can order the ranking (tier B shape_strong: shape's noise 0.34) and the fits decide there."""
    from calibration.replicates import SIMULATOR_SHARE_MIN

    leader_it = next(p for p in iterations if p.number == plan["leader_iteration"])
    leader, partner = plan["leader"], plan["partner"]
    chi2_leader, chi2_partner = common_chi2(leader_it.report or {}, report)
    chi2 = {leader: chi2_leader, partner: chi2_partner}
    partner_passes = (bool(decision and decision.get("accepted")) and not model_fails(report)
                      and report.get("verdict") != Verdict.OUT_OF_REACH and chi2_partner is not None)
    out = {"leader": leader, "partner": partner, "kept_iteration": leader_it.number, "kept_effect": leader,
           "undistinguished": None, "chi2": chi2}
    if chi2_leader is None:  # the leader's report holds no chi2 to compare with: it stays, said plainly
        return {**out, "message": f"{leader} kept: its iteration {leader_it.number} has no chi2 to compare {partner} with"}
    fits = f"chi2 {chi2_leader:.3g} with {leader} (iteration {leader_it.number})" + (
        f", {chi2_partner:.3g} with {partner} (iteration {it.number})" if chi2_partner is not None else "")
    if not partner_passes:
        why = "was not kept" if not (decision and decision.get("accepted")) else "leaves a misfit"
        return {**out, "message": f"{leader} kept: {partner}, aliased with it, fitted in its place {why} ({fits})"}
    gain = chi2_leader - chi2_partner  # > 0: the partner fits better
    if gain <= -UNDISTINGUISHED_CHI2:
        return {**out, "message": f"{leader} kept: it fits better than its alias {partner} ({fits})"}
    base = next((p for p in iterations if p.number == plan["base"]), None)
    diagnosis = ((base.report or {}).get("diagnosis") or {}) if base is not None else {}
    noise = {row.get("effect"): row.get("signature_noise") for row in diagnosis.get("ranking") or []}
    noisy = [e for e in (leader, partner) if (noise.get(e) or 0.0) >= SIMULATOR_SHARE_MIN]
    if gain >= UNDISTINGUISHED_CHI2 and noisy:
        return {**out, "kept_iteration": it.number, "kept_effect": partner,
                "message": (f"{partner} kept: it fits better than its alias {leader} ({fits}); the diagnosis's "
                            f"order rested on noisy probes ({', '.join(f'{e} noise {noise[e]:.2g}' for e in noisy)})")}
    group = next((g for g in diagnosis.get("alias_groups") or [] if {leader, partner} <= set(g.get("effects", []))),
                 None)
    separating = _separating(group, {leader, partner})
    why = ("both bring the fit into the noise" if gain < UNDISTINGUISHED_CHI2 else
           f"{partner} fits better, where the diagnosis ranked {leader} first on probes with little noise")
    return {**out, "undistinguished": sorted(chi2),
            "message": (f"undistinguished: {leader} and {partner}: {why} ({fits}); these measurements do not tell "
                        f"which is missing; iteration {leader_it.number} ({leader}) is shown"
                        + (f"; measure {' / '.join(separating)} more precisely to decide" if separating
                           else "; a test that moves them differently would decide"))}


def _separating(group: dict | None, effects: set[str]) -> list[str]:
    """The measurements an alias group's diagnosis names as separating any of ``effects`` from the others."""
    return sorted({s["separating_measurement"] for s in (group or {}).get("separators", [])
                   if effects & set(s.get("effects", []))})


def _tried_from(iterations: list, base_number: int) -> set[str]:
    return {_record(p).get("next_effect") for p in iterations if _record(p).get("next_base") == base_number} - {None}


def next_step(config, campaign_config: dict, iterations: list, it, report: dict,
              validate: Validate = validated) -> dict[str, Any]:
    """The automatic record of iteration ``it``: its decision, and either the next effect with the
    next iteration's settings (``next_config``, checked by ``validate``) or the reason to stop."""
    decision, base_number = judge_iteration(iterations, it, report)
    record: dict[str, Any] = {"decision": decision, "base_iteration": base_number, "next_effect": None,
                              "next_base": None, "stop_reason": None}
    if report.get("verdict") == Verdict.SUSPECT_MEASUREMENT:
        # a measurement far outside anything the model reaches, which no candidate moves it to: adding
        # physics (or widening an added one) would only bend the parameters towards a wrong number
        return {**record, "stop_reason": StopReason.SUSPECT_MEASUREMENT.value + "; ".join(
            s["message"] for s in report.get("suspect_measurements") or [])}
    refit = refit_plan(iterations, it)
    wide = widening(config, iterations, it, report)
    if wide is not None:
        params = it.parameters
        factors, box = box_widening(iterations, it, report, config.priors)
        factors = [{**f, "high": wide["high"]} if f["name"] == wide["factor"] else f for f in factors]
        if box:
            record["widened_box"] = box
        if refit is not None:  # the partner's strength wants more room: the comparison waits for it
            record["alias_refit"] = refit
        return _configured({**record, "widened": True}, wide["effect"], wide["base"],
                           {**campaign_config, "factors": factors, "fixed_parameters": _fixed(params)}, validate)
    if refit is not None:
        # an alias fitted in place of an effect that passed: keep the better of the two and stop
        settled = settle_alias(iterations, it, report, decision, refit)
        return {**record, "alias_settled": settled, "kept_iteration": settled["kept_iteration"],
                "stop_reason": f"{StopReason.PASSES.value}; {settled['message']}"}
    rejected = decision is not None and not decision["accepted"]
    if rejected and decision.get("turned_off") and not model_fails(report) \
            and report.get("verdict") != Verdict.OUT_OF_REACH:
        # the effect sits at its off strength and the fit is in the noise: this iteration is the base model
        # refitted (its polish found a better base fit than the iteration it was built on), and it is kept
        # without the effect
        return {**record, "kept_iteration": it.number, "stop_reason": (
            f"{StopReason.PASSES.value} with {decision['effect']} at its off strength: the fit does not ask for it, "
            f"and iteration {it.number} is the base model refitted; {decision['effect']} is not added")}
    base = next(p for p in iterations if p.number == base_number) if rejected else it
    base_report = report if base is it else (base.report or {})
    passes = not model_fails(report)
    if not rejected and passes and report.get("verdict") != Verdict.OUT_OF_REACH:
        testable = ((report.get("lack_of_fit") or {}).get("dof") or 0) > 0
        reason = StopReason.PASSES.value if testable else StopReason.UNTESTABLE.value
        if report.get("verdict") == Verdict.PARTLY_CALIBRATED:
            # the whole passes but a test fails its own check: say so where the loop says why it stopped
            reason += f" ({report['verdict']}: {report.get('meaning')})"
        alias = kept_alias(iterations, decision, base_number)
        if alias is not None:
            again = alias_refit(config, campaign_config, iterations, it, alias, validate)
            if again is not None:
                return {**record, **again}
            record["aliased"] = alias
            reason += f"; {alias['message']}"
        return {**record, "stop_reason": reason}
    if it.number >= config.max_iterations:
        return {**record, "stop_reason": StopReason.MAX_ITERATIONS.value}
    diagnosis = base_report.get("diagnosis") or {}
    skip = active_effects(base.parameters) | _tried_from(iterations, base.number) | (
        {decision["effect"]} if rejected else set())
    # "no physical match" and "suspect measurement" offer nothing to add, whatever the ranking holds
    offered = [] if diagnosis.get("verdict") in AGAINST_ADDING else diagnosis.get("indicated", [])
    options = [name for name in offered if name not in skip]
    # base factors pinned at a box edge short of their typical limit: the next iteration gets the room
    factors, box = box_widening(iterations, base, base_report, config.priors)
    if box:
        record["widened_box"] = box
    if not options and box and not rejected:
        # nothing to add, but the optimum sits on a box edge drawn narrower than the parameter's values
        # usually lie: before the loop stops on the diagnosis, the same model runs in the wider box
        return _configured(record, None, base.number, {**campaign_config, "factors": factors,
                                                      "fixed_parameters": _fixed(base.parameters)}, validate)
    if not options:
        record.pop("widened_box", None)
        # a rejected effect with no other candidate left: nothing improves; otherwise the diagnosis
        # of the model as it stands says why no effect is indicated
        reason = StopReason.NOTHING_IMPROVES.value if rejected else \
            f"{StopReason.DIAGNOSIS.value}{diagnosis.get('verdict', 'not run')}"
        pooled = (diagnosis.get("lack_of_fit") or {}).get("p_value")
        if not rejected and diagnosis.get("verdict") == DiagnosisVerdict.NO_MISFIT and pooled is not None:
            # the iteration's report saw a misfit (on one confirmation battery, or a target out of reach);
            # say why the loop still stops
            reason += f" (every battery at the optimum together: lack of fit p {pooled:.2g})"
        if not rejected and diagnosis.get("measure_next"):
            # an honest "inconclusive" says what would decide it; a misfit no candidate matches, where it sits
            advice = "check first" if diagnosis.get("verdict") == DiagnosisVerdict.NO_MATCH else "measure next"
            reason += f"; {advice}: {', '.join(diagnosis['measure_next'])}"
        return {**record, "stop_reason": reason}
    base_config = {**campaign_config, "factors": factors, "fixed_parameters": _fixed(base.parameters)}
    options, tie = cheapest_of_equals(options, diagnosis, base_config, base_report)
    if tie is not None:
        record["tie_break"] = tie
    name = options[0]
    try:
        nxt = with_effect_factor(base_config, name, **effect_hints(base_report, name))
    except ValueError as exc:  # SettingsError included
        return {**record, "stop_reason": _cannot_run(name, exc)}
    if record.get("widened_box"):  # a widened factor the effect supersedes is fixed instead (adding.without_superseded)
        kept = {f["name"] for f in nxt["factors"]}
        record["widened_box"] = [w for w in record["widened_box"] if w["parameter"] in kept] or None
        if record["widened_box"] is None:
            record.pop("widened_box")
    return _configured(record, name, base.number, nxt, validate)


# two candidates' scores closer than this (relative) are one number: the residual space cannot tell them apart
# (with as many free parameters as targets but one, every signature is parallel or anti-parallel to the misfit)
EQUAL_SCORE = 1e-9


def kept_number(number: int, report: dict | None) -> int:
    """The iteration whose model the loop keeps, read off iteration ``number``'s ``report`` (the loop's last so
    far): the one its automatic record names (an alias compared, an effect turned off), else, when the effect it
    added was not accepted, the iteration it was built on, else itself. The library loop's ``LoopResult.final``
    and the service's material card and export read it here, so the model handed on is the model kept."""
    record = (report or {}).get("automatic") or {}
    if record.get("kept_iteration") is not None:
        return int(record["kept_iteration"])
    decision = record.get("decision")
    if decision is not None and not decision.get("accepted") and record.get("base_iteration") is not None:
        return int(record["base_iteration"])
    return number


def may_continue(record: dict | None, number: int) -> bool:
    """Could more iterations change where the loop stopped after iteration ``number`` (its automatic
    ``record``)? When it stopped at the iteration limit, or kept an effect whose alias it had no iteration left
    to fit. A hint for a page's "continue" action; ``machine.extended`` decides by taking the step again."""
    from calibration.settings import MAX_ITERATIONS

    if not record or number >= MAX_ITERATIONS:
        return False
    return record.get("stop_reason") == StopReason.MAX_ITERATIONS or bool(record.get("aliased"))


def cheapest_of_equals(options: list[str], diagnosis: dict, base_config: dict,
                       base_report: dict) -> tuple[list[str], dict | None]:
    """``options`` with the leaders the diagnosis cannot tell apart (equal score test statistic, to
    ``EQUAL_SCORE``) ordered by what a battery of each costs: the spheres of the largest packing with the
    effect on, at the centre of the next iteration's box (``engine.lab.cost``; a DEM step's work is linear in
    the spheres). Between equals the ranking's order was the last digits of two equal numbers; the data choose
    nothing there, the cost does, and the record says so. Returns (options, the tie break or None)."""
    scores = {row.get("effect"): row.get("lm") for row in diagnosis.get("ranking") or []}
    lead = scores.get(options[0]) if options else None
    if lead is None or len(options) < 2:
        return options, None
    equal = [n for n in options if scores.get(n) is not None
             and abs(scores[n] - lead) <= EQUAL_SCORE * max(abs(lead), 1.0)]
    if len(equal) < 2:
        return options, None
    spheres = {}
    for name in equal:
        try:
            spheres[name] = _battery_spheres(with_effect_factor(base_config, name, **effect_hints(base_report, name)))
        except (ValueError, KeyError):  # a set-up the lab refuses: the ranking's order stands
            return options, None
    chosen = sorted(equal, key=lambda n: spheres[n])  # stable: the ranking's order among equal costs
    rest = [n for n in options if n not in equal]
    return chosen + rest, {
        "equal": equal, "spheres": spheres, "chosen": chosen[0],
        "message": (f"{', '.join(equal)} explain the misfit equally (score {lead:.4g}): these measurements cannot "
                    f"tell them apart; {chosen[0]} is tried first, its batteries having the fewest spheres "
                    f"({', '.join(f'{n} {spheres[n]}' for n in equal)}); the others stay offered")}


def _battery_spheres(config: dict) -> int:
    """Spheres of the largest packing of a battery at the centre of ``config``'s factor box."""
    from calibration.conditions import run_spec
    from calibration.settings import LoopSettings
    from engine.lab.cost import estimate

    settings = LoopSettings.model_validate({k: v for k, v in config.items() if k in LoopSettings.model_fields})
    centre = {f.name: 0.5 * (f.low + f.high) for f in settings.factors}
    return estimate(run_spec(settings, centre, 0)).particles


def _fixed(parameters: dict) -> dict:
    """An iteration's fixed parameters with its active effects, as a campaign configuration holds them."""
    fixed = dict(parameters.get("fixed") or {})
    if parameters.get("effects"):
        fixed["effects"] = parameters["effects"]
    return fixed


def _cannot_run(name: str, exc: Exception) -> str:
    return f"{StopReason.CANNOT_RUN.value}{name} cannot run: {getattr(exc, 'message', None) or str(exc)}"


def _configured(record: dict, name: str | None, base_number: int, nxt: dict, validate: Validate) -> dict[str, Any]:
    """The record with the next iteration's validated settings, or the reason they cannot run. ``name``: the
    effect the next iteration adds; None for the same model in the wider box the record's ``widened_box`` says."""
    try:
        validated = validate(nxt)
    except Exception as exc:  # noqa: BLE001 - any refusal of the settings is a reason to stop, worded
        if isinstance(exc, (ValueError, SettingsError)) or hasattr(exc, "message"):
            what = name or "the box widened for " + ", ".join(w["parameter"] for w in record["widened_box"])
            return {**record, "stop_reason": _cannot_run(what, exc)}
        raise
    return {**record, "next_effect": name, "next_base": base_number, "next_config": validated}
