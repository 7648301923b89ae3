"""The calibration loop as a resumable state machine: ask which batteries to run, tell their results,
advance to the next phase. The one home of every step of the loop.

Phases of an iteration (``calibration.vocabulary.Phase``): design -> batteries -> analysis ->
confirmation (``confirmation_seeds`` batteries at the optimum) -> polish (Gauss-Newton on the
batteries, ``calibration.polish``, at the same seeds, when ``polish_when`` says so; after a step, the chosen
point at as many fresh seeds, which the report reads: ``polish_holdout``) -> report -> done;
when the report finds misfit (lack of fit, or a target out of reach) or a conflict (a parameter pinned
at a bound, a prior pulled off), or with ``diagnose_always``: report -> diagnosis (a baseline at the
optimum and each candidate effect, at seeds of their own; one seed first, ``calibration.replicates``) ->
diagnosed (-> diagnosis again for the other seeds when one did not decide) -> done, the ranking stored in
the report and its verdict judged again on the omnibus and the candidates' directed test together. An
iteration after the first starts its design from the batteries earlier ones ran (``calibration.reuse``). In
automatic mode (``calibration.automatic``) a done iteration either configures the next one, with the
indicated effect as a factor, or records why the loop stopped.

Nothing here stores or queues anything. An iteration is any object with ``number``, ``phase``,
``parameters``, ``design``, ``models``, ``optimum``, ``report`` and ``runs`` (the service's database row
or ``calibration.state.IterationState``); a run has ``id``, ``kind``, ``std_order``, ``run_order``,
``natural``, ``coded``, ``seed`` and ``responses``. A driver asks ``awaited(it)`` for the runs the phase
waits for, has those without responses evaluated, then calls ``step`` and applies the ``Transition``
it returns: the new phase, the iteration's new values, the runs to add and, at the end of an
iteration, what follows. The service's runner applies it with a compare-and-swap on the phase (a
restart or a second runner queues no twins); ``calibration.loop`` applies it in memory.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

from . import analysis, attribute, automatic, polish, replicates, reuse, suspect
from .awaiting import awaited, round_runs, runs_of  # noqa: F401  (awaited: the runner's, through machine)
from .design import build_design, design_view
from .errors import LoopFailed, SettingsError
from .records import Measured
from .report import build_report
from .settings import MAX_ITERATIONS, LoopSettings
from .vocabulary import MISFIT_VERDICTS, Phase, PolishJacobian, PolishRule, PolishStage, RunKind

SEED_MAX = 2**31 - 1
DESIGN_SEED_STRIDE = 7919          # the design's seeds of iteration n start at seed + 7919 (n - 1)
CONFIRMATION_SEED_STRIDE = 1_000_003
HOLDOUT_SEED_OFFSET = 250_001      # the held-out round's seeds: the confirmation's base moved by this


@dataclass
class NewRun:
    """A battery to add to the iteration (and to run)."""

    kind: RunKind
    std_order: int
    run_order: int
    natural: dict[str, float]
    coded: dict[str, float]
    seed: int
    is_centre: bool = False
    # a battery an earlier iteration ran (calibration.reuse): its responses and job, nothing to run
    responses: dict[str, Any] | None = None
    job_id: int | None = None
    reused_from: str | None = None


@dataclass
class Transition:
    """What ``step`` decided: move the iteration from ``source`` to ``to`` with ``values`` set and
    ``runs`` added. At the end of an iteration (``to`` is DONE): ``next_settings`` are the loop's
    settings for the next iteration (automatic mode), else ``complete`` ends the loop."""

    source: Phase
    to: Phase
    values: dict[str, Any] = field(default_factory=dict)
    runs: list[NewRun] = field(default_factory=list)
    next_settings: dict[str, Any] | None = None
    complete: bool = False

    @property
    def finished(self) -> bool:
        return self.to == Phase.DONE


@dataclass
class Context:
    """What a step needs besides the iteration: the loop's settings now (``raw``: as stored), the
    measurements, every iteration so far (the automatic mode judges against earlier ones) and how the
    next iteration's settings are checked (the service adds its cost limits)."""

    settings: LoopSettings
    raw: dict[str, Any]
    targets: Sequence[Measured]
    iterations: Sequence[Any]
    validate: Callable[[dict], dict]
    # the measurements left out of the targets, with the reason (calibration.comparable.split): every report names them
    left_out: Sequence[dict[str, Any]] = ()


def records(runs) -> list[list[dict]]:
    """Each run's response records (one list per battery)."""
    return [list((r.responses or {}).values()) for r in runs]


def iteration_parameters(settings: LoopSettings, evaluator: str | None = None) -> dict[str, Any]:
    """What a new iteration records of the settings it runs with (its factors, fixed parameters with
    the active effects apart, options), so the history can show each iteration's model."""
    fixed = dict(settings.fixed_parameters)
    return {"factors": [f.model_dump() for f in settings.factors],
            "fixed": {k: v for k, v in fixed.items() if k != "effects"},
            "effects": fixed.get("effects", {}), "options": dict(settings.options),
            "evaluator": evaluator, "fidelity": settings.fidelity,
            "lab": reuse.lab_json(settings), "setup_key": reuse.setup_key(settings, evaluator)}


def step(ctx: Context, it) -> Transition | None:
    """The iteration's next transition, once every run ``awaited`` has its responses; None at DONE.
    Raises ``LoopFailed`` when the step cannot succeed."""
    phase = Phase(it.phase)
    simple = {Phase.BATTERIES: Phase.ANALYSIS, Phase.CONFIRMATION: Phase.POLISH,
              Phase.DIAGNOSIS: Phase.DIAGNOSED}
    if phase in simple:
        return Transition(phase, simple[phase])
    handler = {Phase.DESIGN: _design, Phase.ANALYSIS: _analysis, Phase.POLISH: _polish,
               Phase.REPORT: _report, Phase.DIAGNOSED: _diagnosed}.get(phase)
    return handler(ctx, it) if handler else None


# -- the steps ----------------------------------------------------------------------------------
def _design(ctx: Context, it) -> Transition:
    s = ctx.settings
    seed = (s.seed + DESIGN_SEED_STRIDE * (it.number - 1)) % SEED_MAX
    try:
        design = build_design(s.factors, s.design, seed)
    except SettingsError as exc:
        raise LoopFailed(f"iteration {it.number}: the design cannot be built: {exc.message}") from exc
    sources = [None] * design.n_runs
    if s.reuse and it.number > 1:
        merged = reuse.with_earlier(design, reuse.earlier_runs(ctx.iterations, it.number, s.fixed_parameters, s.factors,
                                                               it.parameters))
        design, sources = merged.design, merged.sources
    view = design_view(design)
    for row, source in zip(view["runs"], sources):
        row["reused_from"] = source.provenance() if source is not None else None
    view["batteries"] = {"run": sum(src is None for src in sources), "reused": sum(src is not None for src in sources)}
    runs = [NewRun(RunKind.DESIGN, row["std_order"], row["run_order"], row["natural"], row["coded"], row["seed"],
                   is_centre=row["point_type"] == "center",
                   responses=None if src is None else src.responses, job_id=None if src is None else src.job_id,
                   reused_from=None if src is None else src.source)
            for row, src in zip(view["runs"], sources)]
    return Transition(Phase.DESIGN, Phase.BATTERIES, {"design": view}, runs)


def _analysis(ctx: Context, it) -> Transition:
    s = ctx.settings
    try:
        result = analysis.analyse(s, it.design["doe"], runs_of(it, RunKind.DESIGN), ctx.targets)
    except analysis.AnalysisError as exc:
        raise LoopFailed(f"iteration {it.number}: {exc}") from exc
    opt = result["optimum"]
    runs = [NewRun(RunKind.CONFIRMATION, k, k, opt["parameters"], opt["coded"], seed)
            for k, seed in enumerate(_fresh_seeds(ctx, it, s.confirmation_seeds, 0))]
    return Transition(Phase.ANALYSIS, Phase.CONFIRMATION, {"models": result["models"], "optimum": opt}, runs)


def _polish(ctx: Context, it) -> Transition:
    """Start, continue or end the polishing on the batteries (``calibration.polish``)."""
    s = ctx.settings
    state = (it.optimum or {}).get("polish")
    if s.polish_steps == 0 or (state and state["stage"] == PolishStage.DONE):
        return Transition(Phase.POLISH, Phase.REPORT)
    design, models = analysis.fit(it.design["doe"], runs_of(it, RunKind.DESIGN), ctx.targets)
    modelled = [m for m in models if m.fit is not None]
    if state is None:
        confirmations = polish.final_runs(it)
        jacobian, why, anchors = s.polish_jacobian, None, []
        if s.polish_when == PolishRule.SURROGATE_MISSES:
            check = analysis.surrogate_check(s, modelled, it.optimum, records(confirmations),
                                             [r.seed for r in confirmations])
            why, pulled = _added_effect_misfits(s, it, design, modelled, confirmations)
            if check.get("confirmed") is not False and why is None:
                # confirmed, or nothing modelled to polish on
                return Transition(Phase.POLISH, Phase.REPORT, {"optimum": {**it.optimum, "polish": polish.skipped(check)}})
            if check.get("confirmed"):
                # the surfaces predicted the optimum's batteries, so their slopes lead back to their own
                # optimum (the first step would be the batteries' small departure from them, the misfit
                # left where it was): only slopes measured on the batteries can see past it
                jacobian = PolishJacobian.BATTERIES
                # and a local slope cannot see across a saturating response's plateau: where a measured
                # parameter is missed, the surfaces' optimum with it (and with the measured ones its measurement
                # knows better than the targets do) held at its measured value runs too
                anchors = analysis.anchored_points(s, design, modelled, pulled, it.optimum, records(confirmations),
                                                   [r.seed for r in confirmations])
            else:
                why = f"the surfaces missed the confirmation batteries ({check.get('reason')})"
        state, points = polish.start(s, design, modelled, dict(it.optimum["parameters"]),
                                     [r.id for r in confirmations], records(confirmations),
                                     [r.seed for r in confirmations], jacobian=jacobian, why=why, anchors=anchors)
        if not points:
            return Transition(Phase.POLISH, Phase.REPORT, {"optimum": {**it.optimum, "polish": state}})
        return Transition(Phase.POLISH, Phase.POLISH, {"optimum": {**it.optimum, "polish": state}},
                          _polish_runs(state, points))
    if state["stage"] == PolishStage.HOLDOUT:
        state = polish.held_out(s, design, modelled, state, round_runs(it, state))
    else:
        state, points = polish.advance(s, design, modelled, state, round_runs(it, state), s.polish_steps)
        if not points and s.polish_holdout and polish.moved(state):
            # the steps chose among noisy batteries: the report reads the chosen point at seeds it was not chosen on
            state, points = polish.hold_out(design, state,
                                            _fresh_seeds(ctx, it, len(polish.seeds_of(state)), HOLDOUT_SEED_OFFSET))
        if points:
            return Transition(Phase.POLISH, Phase.POLISH, {"optimum": {**it.optimum, "polish": state}},
                              _polish_runs(state, points))
    theta = state["theta"]
    optimum = {**it.optimum, "polish": state, "surrogate_parameters": it.optimum["parameters"],
               "parameters": theta, "coded": {f.name: float(f.to_coded(theta[f.name])) for f in design.factors}}
    return Transition(Phase.POLISH, Phase.REPORT, {"optimum": optimum})


def _added_effect_misfits(s: LoopSettings, it, design, modelled, confirmations) -> tuple[str | None, list[dict]]:
    """Why an iteration whose model has an added effect misses the measurements at the surfaces' optimum
    (a target out of their reach, a parameter pinned at a bound, the confirmation's lack of fit failing,
    a directly measured parameter missed by more than 2 sd), or None; and the priors missed (the
    localisation's ``priors_pulled`` rows, named in the reason too) whatever the reason, for the anchors.
    Such an iteration is judged against the one it was built on, and surfaces fitted on more points than they can follow (reused batteries
    widen their prediction intervals) may pass the surfaces' check with an optimum the batteries refute:
    the effect would be judged on the surfaces' error, not its own. A prior missed is the same sign: two
    level surfaces over a wide box are biased for saturating responses (a friction angle against mu_pp),
    so their optimum can trade a direct measurement for a few targets that the batteries fit better
    nearer the prior (tier B's hertz_strong, session 36: friction_pp 0.91 against a tilt-test prior of
    0.655 +- 0.08 and a truth of 0.6). An iteration without an added effect is not polished for misfit
    alone: the diagnosis decides what its misfit means."""
    if not analysis.active_effects(it.parameters):
        return None, []
    loc = analysis.confirmation_localisation(s, design, modelled, it.optimum, records(confirmations),
                                             [r.seed for r in confirmations])
    # a missed prior is named whatever else is wrong: its anchors are the polish's way off a biased surface's
    # plateau, and a failing lack of fit is what such a plateau leaves (tier B's hertz_strong, session 42: its
    # lack of fit failed, p 0.013, with friction_pp 3.9 sd above its tilt test, and the polish ran no anchor)
    pulled = (loc.conflicts.get("priors_pulled") or []) if loc is not None else []
    missed = [p["meaning"] for p in pulled]
    if any(not row.get("reachable", True) for row in it.optimum.get("reachability") or []):
        why = "a target out of the surfaces' reach"  # the report would say "out of reach"
    elif it.optimum.get("active_bounds"):
        why = "a parameter pinned at a bound"  # where a two-level surface of a saturating response is most biased
    elif loc is not None and loc.lack_of_fit.p_value < analysis.ALPHA:
        why = f"the confirmation's lack of fit fails (p {loc.lack_of_fit.p_value:.2g})"
    elif missed:
        return "; ".join(missed), pulled
    else:
        return None, []
    return "; ".join([why] + missed), pulled


def _fresh_seeds(ctx: Context, it, m: int, offset: int) -> list[int]:
    """``m`` seeds the iteration has not run at, from its base (``CONFIRMATION_SEED_STRIDE`` times its number)
    moved by ``offset``: 0 for the confirmation, ``HOLDOUT_SEED_OFFSET`` for the held-out round. An alias fitted
    in place of an effect that passed takes its leader's base, so the two fits are compared on the same packings
    (common random numbers), not on two draws of the simulator's scatter; where both polished, their held-out
    batteries share packings too."""
    s = ctx.settings
    refit = automatic.refit_plan(ctx.iterations, it) if s.automatic else None
    seed = (s.seed + CONFIRMATION_SEED_STRIDE * (refit["leader_iteration"] if refit else it.number)
            + offset) % SEED_MAX
    taken = {r.seed for r in it.runs}
    out = []
    while len(out) < m:
        while seed in taken:
            seed = (seed + 1) % SEED_MAX
        taken.add(seed)
        out.append(seed)
    return out


def _polish_runs(state: dict, points) -> list[NewRun]:
    out = []
    for k, (natural, coded) in enumerate(points):
        for j, seed in enumerate(polish.round_seeds(state)):
            order = polish.std_order(state, k, j)
            out.append(NewRun(RunKind.POLISH, order, order, natural, coded, seed))
    return out


def _report(ctx: Context, it) -> Transition:
    s = ctx.settings
    confirmations = polish.final_runs(it)
    seeds = [r.seed for r in confirmations]
    design_runs = runs_of(it, RunKind.DESIGN)
    state = (it.optimum or {}).get("polish")
    measured = [(natural, records(runs)) for natural, runs in polish.measured_points(state, it.runs)]
    assessment = analysis.assess(s, it.design["doe"], design_runs, ctx.targets, it.optimum,
                                 records(confirmations), seeds, measured,
                                 polish.seeds_of(state) if measured else None)
    polished = polish.summary(state)
    assessment["polished"] = polish.moved(state)
    report = build_report(s, it.models, it.optimum, confirmations, ctx.targets, assessment,
                          suspect.reach(r.responses for r in it.runs if r.kind != RunKind.DIAGNOSIS))
    report["polish"] = polished
    report["left_out_targets"] = [dict(t) for t in ctx.left_out]
    first = confirmations[0]
    stored = {"job_id": first.job_id, "seed": first.seed, "parameters": first.natural,
              "responses": first.responses, "job_ids": [r.job_id for r in confirmations], "seeds": seeds}
    # a diagnosis needs misfit the parameters cannot absorb: more measured values than free parameters
    diagnosable = ((report.get("lack_of_fit") or {}).get("dof") or 0) > 0
    # in automatic mode an iteration the next one will not build on needs no diagnosis of its own
    rejected = s.automatic and not automatic.builds_on(s, ctx.iterations, it, report)
    # a diagnosis attributes misfit: it runs when the lack of fit fails or a target is out of reach, and
    # when a conflict (a parameter pinned at a bound, a prior pulled off) suggests a misfit the omnibus
    # test cannot see, which the diagnosis's directed test then judges (whatever the surfaces' check says);
    # with diagnose_always, after every report
    misfit = report["verdict"] in MISFIT_VERDICTS or report["suspect"]
    # the diagnosis starts on one seed and runs the others only where they buy power (calibration.replicates)
    plan = analysis.diagnosis_plan(s, it.optimum, it.parameters, replicates.first_stage(seeds, s.adaptive_replicates)) if (
        s.diagnose and diagnosable and (misfit or s.diagnose_always) and not rejected) else []
    if plan:
        runs = [NewRun(RunKind.DIAGNOSIS, k + 1, k + 1, natural, {}, seed) for k, (_, natural, seed) in enumerate(plan)]
        # which battery is which (by standard order), stored so the diagnosis reads it rather than planning again
        report = {**report, "diagnosis_plan": [_plan_entry(name, seed, attribute.STEP) for name, _, seed in plan]}
        return Transition(Phase.REPORT, Phase.DIAGNOSIS, {"report": report, "confirmation": stored}, runs)
    return _finish(ctx, it, Phase.REPORT, report, confirmation=stored)


def _plan_entry(name: str, seed: int, probe: str) -> dict[str, Any]:
    """A diagnosis battery as the report stores it; the probe is named only where it is not the step's, so the
    plans of iterations stored before the top probe existed read the same."""
    return {"effect": name, "seed": seed} if probe == attribute.STEP else {"effect": name, "seed": seed, "probe": probe}


def _diagnosed(ctx: Context, it) -> Transition:
    s = ctx.settings
    confirmations = polish.final_runs(it)
    seeds = [r.seed for r in confirmations]
    runs = sorted(runs_of(it, RunKind.DIAGNOSIS), key=lambda r: r.std_order)
    stored_plan = (it.report or {}).get("diagnosis_plan")
    # iterations stored before the plan was kept with the report are planned again (the same pure function)
    plan = ([(p["effect"], p["seed"], p.get("probe", attribute.STEP)) for p in stored_plan] if stored_plan is not None
            else [(name, seed, attribute.STEP)
                  for name, _, seed in analysis.diagnosis_plan(s, it.optimum, it.parameters, seeds)])
    diagnosis = analysis.diagnose(s, it.design["doe"], runs_of(it, RunKind.DESIGN), ctx.targets, it.optimum,
                                  records(confirmations), seeds,
                                  [(name, seed, list((r.responses or {}).values()), probe)
                                   for (name, seed, probe), r in zip(plan, runs)])
    # the suspects judged again: the model's reach now includes each candidate at a plausible strength (a step
    # probe extrapolated to the top, a top probe as it ran)
    planned = [(name, r.responses) for (name, _, probe), r in zip(plan, runs) if probe == attribute.STEP]
    reach = suspect.reach([*(r.responses for r in it.runs if r.kind != RunKind.DIAGNOSIS),
                           *(responses for name, responses in planned if name == analysis.BASELINE),
                           *suspect.extrapolated_candidates(planned, analysis.BASELINE),
                           *(r.responses for (_, _, probe), r in zip(plan, runs) if probe == attribute.TOP)])
    suspects = suspect.suspects((it.report or {}).get("targets") or [], reach)
    planned_seeds = list(dict.fromkeys(seed for name, seed, _ in plan if name == analysis.BASELINE))
    all_seeds = attribute.signature_seeds(seeds)
    probed_top = list(dict.fromkeys(name for name, _, probe in plan if probe == attribute.TOP))
    if stored_plan is not None:
        if len(planned_seeds) < len(all_seeds):
            more, why = replicates.more_seeds(diagnosis, diagnosis.get("simulator_share"))
        else:
            more, why = False, f"every seed run ({len(planned_seeds)})"
        # a candidate the step's probe saw but could not name is probed at its plausible top too, once
        top = [] if more or suspects else attribute.top_probes(diagnosis, set(probed_top))
        stage = {"seeds": len(planned_seeds), "batteries": len(plan), "more_seeds": more, "why": why}
        if top:
            stage["top_probes"] = top
            stage["why"] += ("; the model misses the measurements and no candidate is named, but "
                             f"{', '.join(top)} explain part of the misfit: probed at their plausible top too")
        stages = [*((it.report or {}).get("diagnosis_stages") or []), stage]
        if more or top:
            done = [seed for seed in seeds if attribute.signature_seeds([seed])[0] in planned_seeds]
            rest = [seed for seed in seeds if seed not in done]
            # more seeds: the step's probes there, and the top's where it ran; a top probe: at the seeds run
            extra = ([(name, natural, seed, attribute.STEP)
                      for name, natural, seed in analysis.diagnosis_plan(s, it.optimum, it.parameters, rest)]
                     + [(name, natural, seed, attribute.TOP)
                        for name, natural, seed in analysis.top_probe_plan(s, it.optimum, probed_top, rest)]
                     if more else
                     [(name, natural, seed, attribute.TOP)
                      for name, natural, seed in analysis.top_probe_plan(s, it.optimum, top, done)])
            runs = [NewRun(RunKind.DIAGNOSIS, len(plan) + k + 1, len(plan) + k + 1, natural, {}, seed)
                    for k, (_, natural, seed, _) in enumerate(extra)]
            report = {**(it.report or {}), "diagnosis_stages": stages,
                      "diagnosis_plan": [*stored_plan, *(_plan_entry(name, seed, probe) for name, _, seed, probe in extra)]}
            return Transition(Phase.DIAGNOSED, Phase.DIAGNOSIS, {"report": report}, runs)
        it_report = {**(it.report or {}), "diagnosis_stages": stages}
    else:
        it_report = it.report or {}
    return _finish(ctx, it, Phase.DIAGNOSED, analysis.diagnosed_report(it_report, diagnosis, suspects))


def extended(ctx: Context, it, more_iterations: int) -> Transition:
    """A completed automatic loop taken up again with ``more_iterations`` beyond its last iteration ``it``:
    the automatic mode decides ``it``'s next step again under the raised ``max_iterations`` (the settings
    the returned transition carries on), and the record it stores says what the loop had stopped for.

    Why: the iteration limit is a budget, not a verdict. A loop that reached it with a step pending (an
    alias to fit in place of the effect kept, an effect to add) says what that step is (tier B's
    cohesion_strong on DEM stopped at 3 naming rolling resistance to fit in cohesion's place); taking it up
    again runs that step with every battery already run kept, where a new campaign would start over.
    SettingsError when the loop is not automatic or not at its end, or when the raised limit still leaves
    nothing to do (the stop was not the limit's: the lack of fit passes, nothing improves)."""
    s = ctx.settings
    if not s.automatic:
        raise SettingsError("only an automatic loop continues by itself; start the next iteration with the "
                            "changes it needs instead", "automatic", conflict=True)
    if it.number != max(p.number for p in ctx.iterations):
        raise SettingsError(f"iteration {it.number} is not the loop's last", "more_iterations", conflict=True)
    if it.phase != Phase.DONE or it.report is None:
        raise SettingsError(f"iteration {it.number} is still running ({it.phase}): the loop has not stopped",
                            "more_iterations", conflict=True)
    limit = it.number + more_iterations
    raised = {**ctx.raw, "max_iterations": limit}
    if limit > MAX_ITERATIONS:
        raise SettingsError(f"{it.number} iterations ran and an automatic loop runs at most "
                            f"{MAX_ITERATIONS}: at most {MAX_ITERATIONS - it.number} more",
                            "more_iterations")
    settings = type(s).model_validate(raised)
    before = (it.report.get("automatic") or {}).get("stop_reason")
    report = {k: v for k, v in it.report.items() if k != "automatic"}
    record = automatic.next_step(settings, raised, ctx.iterations, it, report, ctx.validate)
    following = record.pop("next_config", None)
    if following is None:
        raise SettingsError(f"the loop stopped for a reason more iterations do not change: {record['stop_reason']}",
                            "more_iterations", conflict=True)
    record["continued"] = {"more_iterations": more_iterations, "max_iterations": limit, "stopped_for": before}
    return Transition(Phase.DONE, Phase.DONE, {"report": {**report, "automatic": record}},
                      next_settings=following)


def _finish(ctx: Context, it, source: Phase, report: dict, **values: Any) -> Transition:
    """The iteration is done. In automatic mode the next one is configured with it; otherwise, or when
    the automatic mode stops, the loop is complete."""
    s = ctx.settings
    following = None
    if s.automatic:
        record = automatic.next_step(s, ctx.raw, ctx.iterations, it, report, ctx.validate)
        following = record.pop("next_config", None)
        report = {**report, "automatic": record}
    return Transition(source, Phase.DONE, {"report": report, **values}, next_settings=following,
                      complete=following is None)
