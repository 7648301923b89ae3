"""Gauss-Newton on the batteries themselves, after the confirmation: the loop's polishing phase.

Why: a two-level response surface of a saturating response (friction angle against mu_pp,
anything against an added effect's strength) is biased inside its box, so the surfaces' optimum is
not the simulator's, and an added effect that would fit the measurements can look as if it did
not. The method is cut into rounds a driver can queue and resume (``calibration.machine``):

* round 0, the Jacobian (``polish_jacobian="batteries"``): one point per free factor, a coded step of
  0.1 from the optimum (inward at a bound), each point run at every confirmation seed (common random
  numbers) and averaged over them, as the confirmation is; the targets' rows of J are these forward
  differences, the priors' rows stay analytic. With ``"surfaces"`` (the default) J starts as the fitted
  surfaces' slopes at the optimum and the first step is round 1: Broyden's updates correct it along
  the steps taken, and k x m batteries are saved. Not where the surfaces predicted the optimum's
  batteries and the loop polishes for an added effect's misfit (``calibration.machine``): their slopes
  then lead back to their own optimum, and the forward differences are taken whatever the setting.
  Where the reason is a directly measured parameter the optimum misses, the round also runs anchors,
  points of its profile: the surfaces' optimum with that parameter held at its measured value, and with
  every measured parameter held that its measurement pins better than the targets do
  (``analysis.anchored_points``); the steps start at the best of them if
  the batteries prefer it to the optimum: a local slope cannot see across a saturating response's
  plateau to the fit the measurements point at. An anchor the batteries did not prefer gets one step of its
  own in the first step's round (the slopes carried to it by Broyden's update), beside the optimum's step: the
  anchor's other parameters are the surfaces' guess, and one step puts them where the batteries want them
  before the anchor is given up; the best trial that lowers the misfit is taken;
* rounds 1..: the bounded Gauss-Newton step minimising |r + J du| in the box, tried at full length,
  then (only if that did not lower the batteries' misfit) at half and at quarter length, one round
  each; the first that lowers it is taken and J is updated by Broyden's rule; ``polish_steps`` steps
  taken (starting at an anchor is not one), no improvement at quarter length, or a step below 1e-3
  ends it. One point at a time: the trials used to run side by side, three points per step whether
  the full step worked or not, and the m seeds of one point already keep m workers busy.

* the held-out round (``polish_holdout``, after a polish that took a step): the chosen point once more, at
  fresh seeds no trial was judged on (``hold_out``, ``held_out``). The steps keep whichever trial's batteries
  fit best, and on a simulator whose seeds pair nothing (the DEM engine's packings) choosing among noisy values
  picks the one whose noise helped: read on the same batteries, the fit looks better than it is (DEM's
  hertz_strong, session 40: targets chi2 15.8 on the chosen seeds, 28.4 on 16 others, the truth's 7.3 and 7.6).
  The report, its lack of fit and the diagnosis read the held-out batteries (``final_runs``); the intervals'
  likelihood ratio stays among the points measured at the polish's own seeds (``measured_points``).

The state is a JSON dict kept in the iteration's optimum, so every round survives a restart. Costs
(free factors + trials) x confirmation seeds batteries (a step costs one trial when its full length
works, up to three), all of a round queued at once, and the held-out round's confirmation seeds more.
"""
from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from calibration import calibrate as cal
from calibration.awaiting import ROUND
from calibration.vocabulary import PolishJacobian, PolishStage, RunKind

CODED_STEP = 0.1
SHRINKS = (1.0, 0.5, 0.25)
MIN_STEP = 1e-3


def _residuals(config, design, modelled, theta: dict, records: list[list[dict]], seeds: list[int]):
    """Residuals of one point from its batteries at ``seeds`` (one record list per seed)."""
    conf = cal.confirm(modelled, records, seeds)
    return cal.residuals_at(design, modelled, theta, conf, [p.model_dump() for p in config.priors],
                            config.default_relative_uncertainty, config.model_discrepancy)


def _point(design, theta: dict) -> tuple[dict, dict]:
    natural = {k: float(v) for k, v in theta.items()}
    coded = {f.name: float(f.to_coded(natural[f.name])) for f in design.factors}
    return natural, coded


def _step_points(design, state: dict) -> list[tuple[dict, dict]]:
    """The first trial point of the next Gauss-Newton step from the state's r and J (its full length;
    the direction is kept in the state for the shorter trials), or [] when the step is negligible."""
    current = SimpleNamespace(r=np.array(state["r"]), J=np.array(state["J"]), free=state["free"])
    step = cal.gauss_newton_step(design, current, state["theta"])
    if float(np.max(np.abs(step))) < MIN_STEP:
        return []
    state.update(direction=[float(v) for v in step], shrink=0)
    return [_shrunk(design, state)]


def _shrunk(design, state: dict) -> tuple[dict, dict]:
    """The trial point of the state's step at its current length (``SHRINKS[state["shrink"]]``)."""
    step = SHRINKS[state["shrink"]] * np.array(state["direction"])
    return _point(design, cal.move(design, state["theta"], state["free"], step))


def seeds_of(state: dict) -> list[int]:
    """The seeds every polishing point runs at (a state stored before there were several: its one seed)."""
    return list(state.get("seeds") or [state["seed"]])


def start(config, design, modelled, theta: dict, run_ids: list[int], records: list[list[dict]], seeds: list[int],
          jacobian: str | None = None, why: str | None = None, anchors: list[dict] | None = None
          ) -> tuple[dict, list[tuple[dict, dict]]]:
    """State at the surfaces' optimum (its confirmation runs ``run_ids``, their ``records`` at ``seeds``)
    and the first round's points (natural, coded; [] with the state done when the surfaces' slopes give
    no step); each point is queued once per seed. ``jacobian`` overrides ``config.polish_jacobian`` (the
    loop measures the slopes on the batteries where the surfaces predicted the optimum's batteries);
    ``why`` is kept for the report. ``anchors`` ({"held", "parameters"}, natural; with the batteries'
    Jacobian only; ``analysis.anchored_points``) run in the Jacobian's round, and the best of them that the
    batteries prefer to the optimum is where the steps start (``machine``: the surfaces' optimum with a
    missed measured parameter held at its measured value)."""
    res = _residuals(config, design, modelled, theta, records, seeds)
    jacobian = PolishJacobian(jacobian or config.polish_jacobian)
    state = {"round": 0, "stage": PolishStage.JACOBIAN.value, "theta": dict(theta), "run_ids": list(run_ids), "seeds": list(seeds),
             "chi2_start": res.chi2(), "chi2": res.chi2(), "r": res.r.tolist(), "J": res.J.tolist(),
             "free": list(res.free), "n_targets": len(res.keys), "steps": 0, "batteries": 0, "h": [],
             "jacobian": jacobian.value}
    if why:
        state["why"] = why
    if jacobian == PolishJacobian.SURFACES:
        # the surfaces' slopes at the optimum start the Broyden updates: no round of forward differences
        # (k x m batteries), which on the engine's scatter are as noisy as the slopes they replace
        points = _step_points(design, state)
        if not points:
            return _done(state), []
        state.update(stage=PolishStage.STEP.value, round=1)
        return state, points
    points = []
    for j, name in enumerate(res.free):
        u = float(design.factor(name).to_coded(theta[name]))
        h = CODED_STEP if u + CODED_STEP <= 1.0 else -CODED_STEP
        state["h"].append(h)
        points.append(_point(design, cal.move(design, theta, res.free, np.eye(len(res.free))[j] * h)))
    if anchors:
        state["anchors"] = [{"held": dict(a["held"]), "parameters": dict(a["parameters"])} for a in anchors]
        points += [_point(design, a["parameters"]) for a in anchors]
    return state, points


def skipped(check: dict) -> dict:
    """The state of an iteration that does not polish (``polish_when="surrogate_misses"``): the surfaces
    predicted its confirmation batteries, whose reason is kept for the report."""
    return {"stage": PolishStage.DONE.value, "skipped": check.get("reason") or check.get("verdict"), "steps": 0, "batteries": 0}


def round_seeds(state: dict) -> list[int]:
    """The seeds the state's current round runs its points at: the held-out seeds in the held-out round, else
    the polish's own."""
    if state.get("stage") == PolishStage.HOLDOUT:
        return list(state["holdout_seeds"])
    return seeds_of(state)


def hold_out(design, state: dict, seeds: list[int]) -> tuple[dict, list[tuple[dict, dict]]]:
    """The held-out round after a polish that took a step: the state waiting for it and its one point, the
    chosen optimum, to be run at ``seeds`` (as many as the polish's own, none of them among the seeds any point
    of the iteration ran at; ``calibration.machine`` chooses them)."""
    if len(seeds) != len(seeds_of(state)) or set(seeds) & set(seeds_of(state)):
        raise ValueError("the held-out seeds must be as many as the polish's and none of them")
    state = dict(state)
    state.update(stage=PolishStage.HOLDOUT.value, round=state["round"] + 1, holdout_seeds=[int(v) for v in seeds])
    state["holdout_round"] = state["round"]
    return state, [_point(design, state["theta"])]


def held_out(config, design, modelled, state: dict, round_runs: list) -> dict:
    """The state once the held-out round ran (``round_runs``, one per held-out seed): the final runs are theirs,
    and their chi2 (the same objective as the steps', priors included) is kept beside the polish's own."""
    state = dict(state)
    records = [list((run.responses or {}).values()) for run in round_runs]
    res = _residuals(config, design, modelled, state["theta"], records, [r.seed for r in round_runs])
    state.update(stage=PolishStage.DONE.value, run_ids=[r.id for r in round_runs],
                 holdout_chi2=res.chi2() if len(res.keys) == state["n_targets"] else None,
                 batteries=state["batteries"] + len(round_runs))
    return state


def std_order(state: dict, point: int, seed_index: int) -> int:
    """std_order of the run of ``point`` (0-based, in the round) at the ``seed_index``-th seed."""
    return state["round"] * ROUND + point * len(seeds_of(state)) + seed_index + 1


def advance(config, design, modelled, state: dict, round_runs: list, max_steps: int
            ) -> tuple[dict, list[tuple[dict, dict]]]:
    """Evaluate a finished round (its runs in std_order: each point's runs at every seed in turn); the
    new state and the next round's points ([] when polishing is over: ``state["stage"] == "done"``)."""
    state = dict(state)
    state["batteries"] += len(round_runs)
    anchor_steps = []
    n_t = state["n_targets"]
    seeds = seeds_of(state)
    m = len(seeds)
    points = [round_runs[i:i + m] for i in range(0, len(round_runs), m)]
    records = [[list((run.responses or {}).values()) for run in runs] for runs in points]
    if state["stage"] == PolishStage.JACOBIAN:
        J = np.array(state["J"])
        r0 = np.array(state["r"])
        k = len(state["h"])
        for j, (runs, recs) in enumerate(zip(points[:k], records[:k])):
            res_j = _residuals(config, design, modelled, runs[0].natural, recs, seeds)
            if len(res_j.keys) == n_t:
                J[:n_t, j] = (res_j.r[:n_t] - r0[:n_t]) / state["h"][j]
        state["J"] = J.tolist()
        best = None
        state["anchors"] = [dict(a) for a in state.get("anchors") or []] or None
        measured = []
        for which, (anchor, runs, recs) in enumerate(zip(state["anchors"] or [], points[k:], records[k:])):
            res_a = _residuals(config, design, modelled, runs[0].natural, recs, seeds)
            anchor["chi2"] = res_a.chi2() if len(res_a.keys) == n_t else None
            if anchor["chi2"] is None:
                continue
            measured.append((which, runs, res_a))
            if anchor["chi2"] < (best[1].chi2() if best else state["chi2"]):
                best = (runs, res_a, anchor)
        at_optimum = state
        if best is not None:
            best[2]["taken"] = True
            state = _take(design, state, best[0], best[1], step=False)
        anchor_steps = _anchor_steps(design, at_optimum, [m for m in measured if not state["anchors"][m[0]].get("taken")])
    else:
        taken = None
        trials = state.pop("trials", None) or [None] * len(points)
        for which, runs, recs in zip(trials, points, records):
            res_k = _residuals(config, design, modelled, runs[0].natural, recs, seeds)
            chi2 = res_k.chi2() if len(res_k.keys) == n_t else None
            if which is not None:  # a step from an anchor (``_anchor_steps``), tried beside the current point's
                state["anchors"][which]["step_chi2"] = chi2
            if chi2 is not None and chi2 < (taken[1].chi2() if taken else state["chi2"]):
                taken = (runs, res_k, which)
        if taken is not None and taken[2] is not None:
            state["anchors"][taken[2]]["step_taken"] = True
        taken = taken[:2] if taken is not None else None
        if taken is None:
            if "direction" in state and state["shrink"] + 1 < len(SHRINKS):
                # the trial did not lower the misfit: the same step, shorter, in a round of its own (one
                # point at a time: a step that works at full length costs one point, not three)
                state.update(shrink=state["shrink"] + 1, round=state["round"] + 1)
                return state, [_shrunk(design, state)]
            return _done(state), []
        state = _take(design, state, *taken)
    if state["steps"] >= max_steps:
        return _done(state), []
    points = _step_points(design, state)
    if state["stage"] == PolishStage.JACOBIAN and anchor_steps:
        # the anchors' own steps ride in the first step's round, after the current point's (if it has one)
        state["trials"] = [None] * len(points) + [which for which, _ in anchor_steps]
        points = points + [point for _, point in anchor_steps]
    if not points:
        return _done(state), []
    state.update(stage=PolishStage.STEP.value, round=state["round"] + 1)
    return state, points


def _anchor_steps(design, at_optimum: dict, measured: list) -> list[tuple[int, tuple[dict, dict]]]:
    """(anchor index, trial point) of one Gauss-Newton step from each anchor the batteries did not prefer
    (``measured``: (its index, its runs, its residuals)), with the slopes measured at the optimum carried to the
    anchor by Broyden's update along the move. Why: an anchor holds a measured parameter at its measured value
    but takes the others from the surfaces' conditional optimum, which the batteries may not share (on DEM,
    hertz_strong's held every measured parameter: 2 % of density off the bulk density measured to 0.4 %);
    one step puts the others where the batteries want them before the anchor is judged."""
    out = []
    for which, runs, res_a in measured:
        points = _step_points(design, _take(design, at_optimum, runs, res_a, step=False))
        if points:
            out.append((which, points[0]))
    return out


def _take(design, state: dict, runs: list, res_k, step: bool = True) -> dict:
    """The state moved to the point ``runs`` ran at (their residuals ``res_k``), J updated along the move;
    ``step`` counts it among the Gauss-Newton steps (``polish_steps`` bounds those). Starting at an anchor is no
    step: counted as one, it cost hertz_strong on DEM (session 42) one of its three steps, and the polish stopped
    with its misfit still falling (chi2 24.9 at the anchor, 22.0, 15.9); the third step (session 43) reached 13.4,
    and at 24 seeds the fit's RMS came to 1.31 x the truth's from 2.35 x at 16."""
    natural = runs[0].natural
    du = np.array([float(design.factor(n).to_coded(natural[n]) - design.factor(n).to_coded(state["theta"][n]))
                   for n in state["free"]])
    J = np.array(state["J"])
    dr = res_k.r - np.array(state["r"])
    if float(du @ du) > 0.0:
        J = J + np.outer(dr - J @ du, du) / float(du @ du)  # Broyden's good update
    state = dict(state)
    state.pop("run_id", None)
    state.update(theta={n: float(v) for n, v in natural.items()}, run_ids=[r.id for r in runs],
                 chi2=res_k.chi2(), r=res_k.r.tolist(), J=J.tolist(), steps=state["steps"] + int(step))
    return state


def moved(state: dict | None) -> bool:
    """Whether the polish left the surfaces' optimum: a step taken or the steps started at an anchor."""
    if not state or "skipped" in state:
        return False
    return state.get("steps", 0) > 0 or any(a.get("taken") for a in state.get("anchors") or [])


def _done(state: dict) -> dict:
    state = dict(state)
    state.update(stage=PolishStage.DONE.value)
    return state


def final_runs(it) -> list:
    """The batteries at the iteration's final optimum, one per seed: the best polishing point's, else
    the confirmation's ([] before the confirmation is queued)."""
    state = (it.optimum or {}).get("polish") or {}
    ids = state.get("run_ids") or ([state["run_id"]] if state.get("run_id") is not None else [])
    by_id = {r.id: r for r in it.runs}
    runs = [by_id[i] for i in ids if i in by_id]
    if runs and runs[0].kind == RunKind.POLISH:
        return runs
    return sorted((r for r in it.runs if r.kind == RunKind.CONFIRMATION), key=lambda r: r.std_order)


def measured_points(state: dict | None, runs) -> list[tuple[dict, list]]:
    """Every point the polish measured at all of its seeds, the surfaces' optimum (its confirmation) first:
    (natural parameters, its runs in seed order), for the report's intervals (``intervals.widen_to_measured``).
    A point whose runs are not all there at the polish's seeds, with responses, is left out, and so is the
    held-out round (the chosen point again, at other seeds: the likelihood ratio compares points on common seeds)."""
    if not state or "skipped" in state:
        return []
    seeds = seeds_of(state)
    m = len(seeds)
    groups: dict[tuple[int, int], list] = {}
    for run in sorted((r for r in runs if r.kind == RunKind.POLISH), key=lambda r: r.std_order):
        rnd = run.std_order // ROUND
        if rnd == state.get("holdout_round"):  # the chosen point again, at seeds of its own: not a section
            continue
        groups.setdefault((rnd, (run.std_order - rnd * ROUND - 1) // m), []).append(run)
    confirmation = sorted((r for r in runs if r.kind == RunKind.CONFIRMATION), key=lambda r: r.std_order)
    out = []
    for group in [confirmation] + [groups[k] for k in sorted(groups)]:
        if [r.seed for r in group] == seeds and all(r.responses for r in group):
            out.append((dict(group[0].natural), group))
    return out


def summary(state: dict | None) -> dict[str, Any] | None:
    """What the report shows of the polishing."""
    if not state:
        return None
    if "skipped" in state:
        return {"steps": 0, "batteries": 0, "skipped": state["skipped"]}
    return {"chi2_start": state["chi2_start"], "chi2": state["chi2"], "steps": state["steps"],
            "batteries": state["batteries"], "parameters": state["theta"], "why": state.get("why"),
            "jacobian": state.get("jacobian", PolishJacobian.BATTERIES.value), "anchors": state.get("anchors"),
            "seeds": seeds_of(state), "holdout_seeds": state.get("holdout_seeds"),
            "holdout_chi2": state.get("holdout_chi2")}
