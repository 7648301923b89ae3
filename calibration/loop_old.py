"""The calibration loop on plain records: calibrate -> localise -> attribute -> add -> confirm.

``CalibrationLoop(targets, evaluator, config)`` runs iterations with any batch evaluator
(``calibration.evaluators``): ``iterate`` calibrates one configuration (design, fits, optimum,
confirmation, localisation), ``diagnose`` runs the candidate batteries at the optimum and ranks
the effects, ``with_effect`` builds the next configuration with an effect's strength as one more
design factor, ``accept`` decides whether the effect earned its place, and ``run`` does all of it
until the lack-of-fit test passes, nothing improves, or the iteration budget is spent.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

from engine.candidates import candidates as all_candidates
from engine.effects.base import Candidate
from engine.lab.spec import MicroParameters

from . import calibrate as cal
from . import parameters as params_mod
from . import stats
from .attribute import Attribution, Signature, attribute, signature_seeds, signature_vector
from .decisions import Decision, effect_range, judge, widened_top
from .evaluators import BatchEvaluator
from .fitting import TargetModel, fit_targets, run_values
from .localise import Localisation, Residuals, localise
from .records import Measured


@dataclass
class LoopConfig:
    factors: list[dict]                     # {name, low, high, unit?, log?}; names: calibration.parameters
    fixed: dict[str, Any] = field(default_factory=dict)      # MicroParameters fields (+ effects)
    priors: list[dict] = field(default_factory=list)         # {parameter, value, uncertainty, source?}
    constraints: list[str] = field(default_factory=list)
    centre_runs: int = 3
    confirmation_seeds: int = 2
    default_relative_uncertainty: float = 0.05
    max_iterations: int = 3
    max_refinements: int = 0
    refine_shrink: float = 0.35
    candidates: list[str] | None = None      # None: every registered candidate
    # diagnose (and run the directed test) after every iteration, not only a failing or suspect one
    diagnose_always: bool = False
    fidelity: str | None = None              # the evaluator's lab fidelity (None: any, e.g. the stand-in)
    seed: int = 0

    def __post_init__(self):
        for f in self.factors:
            params_mod.check_factor(f["name"])
        if self.confirmation_seeds < 2:
            raise ValueError("confirmation_seeds must be at least 2 (the seed-to-seed scatter at the optimum)")


@dataclass
class Iteration:
    number: int
    factors: list[dict]
    fixed: dict[str, Any]
    design: Any
    models: list[TargetModel]
    result: Any                             # doe.optimise.CalibrationResult
    confirmation: cal.Confirmation
    adequacy: cal.Adequacy
    residuals: Residuals
    localisation: Localisation
    polish_batteries: int = 0
    added_effect: str | None = None
    runs: int = 0
    theta: dict[str, float] = field(default_factory=dict)   # calibrated factors (after polishing)

    @property
    def parameters(self) -> dict[str, Any]:
        """Full parameter dict at the optimum (fixed values, effects, calibrated factors)."""
        return params_mod.apply(self.fixed, self.theta)

    @property
    def effects(self) -> list[str]:
        active = set((self.fixed.get("effects") or {}))
        active |= {f["name"].split(".")[1] for f in self.factors if f["name"].startswith("effects.")}
        shaped = self.fixed.get("clump_aspect_ratio", 1.0) != 1.0
        if shaped or any(f["name"] == "clump_aspect_ratio" for f in self.factors):
            active.add("particle_shape")
        return sorted(active)

    def error(self) -> dict[str, Any]:
        """Weighted error of this iteration, overall and per test, against its noise band."""
        r = self.residuals.r_targets
        lof = self.localisation.lack_of_fit
        return {"chi2": float(r @ r), "chi2_per_dof": lof.per_dof, "dof": lof.dof, "noise_band": list(lof.noise_band),
                "rms_standardised": stats.weighted_rms(r) if r.size else None,
                "per_test": {t["test"]: t["chi2"] for t in self.localisation.tests},
                "lack_of_fit_p": lof.p_value}

    def to_dict(self) -> dict[str, Any]:
        return {"number": self.number, "effects": self.effects, "added_effect": self.added_effect,
                "factors": self.factors, "parameters": self.theta, "surrogate_optimum": self.result.parameters,
                "parameter_std": self.result.parameter_std, "error": self.error(),
                "adequacy": self.adequacy.to_dict(), "localisation": self.localisation.to_dict(),
                "polish_batteries": self.polish_batteries, "runs": self.runs}


@dataclass
class Diagnosis:
    iteration: int
    attribution: Attribution
    signatures: list[Signature]

    def to_dict(self) -> dict[str, Any]:
        return {"iteration": self.iteration, **self.attribution.to_dict()}


@dataclass
class LoopResult:
    iterations: list[Iteration]
    diagnoses: list[Diagnosis]
    decisions: list[Decision]
    stop_reason: str

    @property
    def final(self) -> Iteration:
        accepted = [self.iterations[0]] + [it for it, d in zip(self.iterations[1:], self.decisions) if d.accepted]
        return accepted[-1]

    def history(self) -> list[dict[str, Any]]:
        return [{"number": it.number, "effects": it.effects, "added_effect": it.added_effect,
                 "chi2_per_dof": it.error()["chi2_per_dof"], "error": it.error(),
                 "parameters": it.theta, "verdict": verdict_of(it)} for it in self.iterations]


def verdict_of(it: Iteration) -> str:
    """One verdict per iteration, never two that contradict each other."""
    if not it.adequacy.adequate:
        return "surrogate inadequate"
    if not it.localisation.fails:
        return "calibrated"
    unreachable = [r for r in it.localisation.reachability if not r.get("reachable", True)]
    return "targets out of reach" if unreachable else "model misses the measurements"


class CalibrationLoop:
    def __init__(self, targets: Sequence[Measured], evaluator: BatchEvaluator, config: LoopConfig):
        self.targets = list(targets)
        self.evaluator = evaluator
        self.config = config

    # -- one calibration ---------------------------------------------------------------------
    def _evaluate(self, fixed: dict, points: list[dict[str, float]], seeds: list[int]) -> list[list[dict]]:
        return self.evaluator([(params_mod.apply(fixed, p), int(s)) for p, s in zip(points, seeds)])

    def confirmation_seeds(self, number: int) -> list[int]:
        return [1_000_003 * (self.config.seed + 1) + 7 * number + j for j in range(self.config.confirmation_seeds)]

    def iterate(self, factors: list[dict], fixed: dict, number: int = 1, added_effect: str | None = None) -> Iteration:
        """Design, fit, optimum, confirmation at the optimum; where the surfaces miss the batteries
        there, Gauss-Newton steps on the batteries themselves and, if they still miss, one narrower
        design about the optimum (``refine_shrink`` of each range); then localise."""
        c = self.config
        factors = [dict(f) for f in factors]
        floors = {f["name"]: f["low"] for f in factors if f["name"].startswith("effects.") or
                  f["name"] == "clump_aspect_ratio"}
        runs_total, steps_total = 0, 0
        for refinement in range(c.max_refinements + 1):
            design = cal.build_design(factors, c.centre_runs, c.seed + 7919 * number + 104729 * refinement)
            records = design.records("std")
            runs = self._evaluate(fixed, [{f.name: r[f.name] for f in design.factors} for r in records],
                                  [r["seed"] for r in records])
            models = fit_targets(design, runs, self.targets)
            priors = [p for p in c.priors if p["parameter"] in design.names]
            result = cal.optimum(models, default_relative=c.default_relative_uncertainty, priors=priors,
                                 constraints=c.constraints, seed=c.seed + number)
            seeds = self.confirmation_seeds(number)
            theta = dict(result.parameters)
            conf = cal.confirm(models, self._evaluate(fixed, [theta] * len(seeds), seeds), seeds)
            adequacy = cal.adequacy(models, result, conf)
            runs_total += len(runs) + len(seeds)
            if not adequacy.adequate:
                theta, conf, steps = self._polish(design, models, fixed, theta, conf, priors)
                runs_total += steps * len(seeds)
                steps_total += steps
                adequacy = cal.adequacy(models, result, conf, at=theta)
            if adequacy.adequate or refinement == c.max_refinements:
                break
            factors = cal.narrowed(factors, theta, shrink=c.refine_shrink, floors=floors)
        residuals = self.residuals(design, models, theta, conf, priors)
        box = self._user_box(factors)
        loc = localise(residuals, active_bounds=cal.active_bounds(design, theta, box),
                       priors=cal.prior_rows(priors, theta), reachability=result.reachability, seed=c.seed + number)
        return Iteration(number, factors, fixed, design, models, result, conf, adequacy, residuals, loc,
                         steps_total, added_effect, runs_total, theta)

    def _user_box(self, factors: list[dict]) -> dict[str, tuple[float, float]]:
        """Bounds that mean something to the user: the configured ranges (a narrowed design's edges
        are not conflicts), and an added effect's own range."""
        box = {f["name"]: (f["low"], f["high"]) for f in factors}
        box.update({f["name"]: (f["low"], f["high"]) for f in self.config.factors})
        return box

    def _polish(self, design, models, fixed, theta, conf, priors, max_steps: int = 6, coded_step: float = 0.1):
        """Bounded Gauss-Newton on the batteries themselves, from the surfaces' optimum.

        Why: a two-level surface of a saturating response is biased inside its box, so its optimum
        is not the simulator's, and its gradients can point the wrong way too. The Jacobian is
        therefore taken from the batteries by forward differences of ``coded_step`` (inward at a
        bound, same seeds: common random numbers), updated by Broyden's rule after each step; each
        step minimises |r + J du| inside the box and is kept only if the batteries' misfit falls.
        Costs (k + steps) x seeds batteries.
        """
        seeds = conf.seeds
        res = self.residuals(design, models, theta, conf, priors)
        chi2 = res.chi2()
        taken = 0
        n_t = len(res.keys)
        J = res.J.copy()
        for j, name in enumerate(res.free):
            f = design.factor(name)
            u = float(f.to_coded(theta[name]))
            h = coded_step if u + coded_step <= 1.0 else -coded_step
            trial = cal.move(design, theta, res.free, np.eye(len(res.free))[j] * h)
            trial_conf = cal.confirm(models, self._evaluate(fixed, [trial] * len(seeds), seeds), seeds)
            taken += 1
            trial_res = self.residuals(design, models, trial, trial_conf, priors)
            if len(trial_res.keys) == n_t:
                J[:n_t, j] = (trial_res.r[:n_t] - res.r[:n_t]) / h
        res.J = J
        for _ in range(max_steps):
            step = cal.gauss_newton_step(design, res, theta)
            if float(np.max(np.abs(step))) < 1e-3:
                break
            accepted = False
            for shrink in (1.0, 0.5, 0.25):
                trial = cal.move(design, theta, res.free, shrink * step)
                trial_conf = cal.confirm(models, self._evaluate(fixed, [trial] * len(seeds), seeds), seeds)
                taken += 1
                trial_res = self.residuals(design, models, trial, trial_conf, priors)
                if trial_res.chi2() < chi2:
                    du = np.array([float(design.factor(n).to_coded(trial[n]) - design.factor(n).to_coded(theta[n]))
                                   for n in res.free])
                    dr = trial_res.r - res.r
                    J = J + np.outer(dr - J @ du, du) / float(du @ du)     # Broyden's good update
                    trial_res.J = J
                    theta, conf, res, chi2, accepted = trial, trial_conf, trial_res, trial_res.chi2(), True
                    break
            if not accepted:
                break
        return theta, conf, taken

    def residuals(self, design, models: list[TargetModel], theta: dict[str, float], conf: cal.Confirmation,
                  priors: list[dict]) -> Residuals:
        return cal.residuals_at(design, models, theta, conf, priors, self.config.default_relative_uncertainty)

    # -- diagnosis ---------------------------------------------------------------------------
    def candidate_pool(self, it: Iteration) -> list[Candidate]:
        pool = all_candidates()
        names = self.config.candidates or list(pool)
        return [pool[n] for n in names if n not in it.effects and pool[n].applies_to(self.config.fidelity)]

    def diagnose(self, it: Iteration) -> Diagnosis:
        base = it.parameters
        seeds = it.confirmation.seeds
        cands = self.candidate_pool(it)
        points, steps, refs = [], [], []
        for c in cands:
            if c.is_switch:
                ref = float(c.reference(MicroParameters.model_validate(base)))
                points.append(params_mod.apply(base, {c.factor: ref}))
                steps.append(1.0)
                refs.append(ref)
            else:
                points.append(params_mod.apply(base, {c.factor: (c.off_value or 0.0) + c.step}))
                steps.append(c.step)
                refs.append(None)
        # a baseline and each candidate at seeds of their own (attribute.signature_seeds says why)
        sig_seeds = signature_seeds(seeds)
        n = len(sig_seeds)
        requests = [(base, s) for s in sig_seeds] + [(p, s) for p in points for s in sig_seeds] if points else []
        results = self.evaluator(requests) if requests else []
        res = it.residuals
        baseline = [run_values(r) for r in results[:n]]
        signatures = []
        for k, c in enumerate(cands):
            on = [run_values(r) for r in results[n + k * n:n + (k + 1) * n]]
            signatures.append(Signature(c, signature_vector(res, on, baseline, steps[k]), steps[k], refs[k]))
        labels = [k.label for k in res.keys]
        att = attribute(it.localisation, res.r, res.M(), signatures, labels)
        it.localisation = it.localisation.with_directed(att.directed)  # now judged on both tests
        return Diagnosis(it.number, att, signatures)

    # -- adding an effect ----------------------------------------------------------------------
    def with_effect(self, it: Iteration, diagnosis: Diagnosis | None, name: str,
                    strength_range: tuple[float, float] | None = None) -> tuple[list[dict], dict]:
        """Next iteration's factors and fixed parameters, with ``name``'s strength as a factor."""
        c = all_candidates()[name]
        factors = [dict(f) for f in it.factors]
        fixed = dict(it.fixed)
        if strength_range is not None:
            low, high = strength_range
            factors.append({"name": c.factor, "low": low, "high": high, "log": c.is_switch})
            return factors, fixed
        ranked = next((r for r in diagnosis.attribution.ranking if r.name == name), None) if diagnosis else None
        reference = float(c.reference(MicroParameters.model_validate(it.parameters))) if c.is_switch else None
        low, high, log = effect_range(c, ranked.strength if ranked else None, reference)
        factors.append({"name": c.factor, "low": low, "high": high, "log": log})
        return factors, fixed

    def iterate_effect(self, factors: list[dict], fixed: dict, number: int, name: str) -> Iteration:
        """``iterate`` with an effect's strength as a factor; a strength pinned at the top of its
        range, pushing outward, is given a range twice as wide (``decisions.widened_top``) and the
        iteration redone once."""
        c = all_candidates()[name]
        it = self.iterate(factors, fixed, number, added_effect=name)
        pinned = any(b["parameter"] == c.factor and b["side"] == "high"
                     for b in it.localisation.conflicts["active_bounds"])
        top = widened_top(c, factors[-1]["high"]) if pinned else None
        if top is not None:
            wider = [dict(f) for f in factors[:-1]] + [{**factors[-1], "high": top}]
            again = self.iterate(wider, fixed, number, added_effect=name)
            again.runs += it.runs
            return again
        return it

    def accept(self, before: Iteration, after: Iteration, name: str) -> Decision:
        c = all_candidates()[name]
        return judge(c, chi2_before=before.residuals.chi2(), chi2_after=after.residuals.chi2(),
                     n_residuals=before.residuals.r.size, free_before=sum(before.residuals.absorbing),
                     free_after=sum(after.residuals.absorbing),
                     lof_p_before=before.localisation.lack_of_fit.p_value,
                     lof_p_after=after.localisation.lack_of_fit.p_value, strength=after.theta.get(c.factor))

    # -- the whole loop -------------------------------------------------------------------------
    def run(self) -> LoopResult:
        c = self.config
        current = self.iterate([dict(f) for f in c.factors], dict(c.fixed), 1)
        iterations, diagnoses, decisions = [current], [], []
        number = 1
        while True:
            loc = current.localisation
            # a passing omnibus test with no conflict ends it; a conflict (a parameter pinned at a
            # bound, a prior pulled off, a target out of reach) asks the directed test first, as
            # diagnose_always does every time
            if not loc.fails and not loc.suspect and not c.diagnose_always:
                return LoopResult(iterations, diagnoses, decisions, "lack of fit passes")
            if number >= c.max_iterations:
                return LoopResult(iterations, diagnoses, decisions, "lack of fit passes" if not loc.fails
                                  else "maximum number of iterations reached")
            diag = self.diagnose(current)
            diagnoses.append(diag)
            if not current.localisation.fails:
                return LoopResult(iterations, diagnoses, decisions, "lack of fit passes")
            options = diag.attribution.indicated()
            if not options:
                return LoopResult(iterations, diagnoses, decisions, f"diagnosis {diag.attribution.verdict}")
            accepted = None
            for name in options[:2]:
                number += 1
                factors, fixed = self.with_effect(current, diag, name)
                nxt = self.iterate_effect(factors, fixed, number, name)
                iterations.append(nxt)
                decision = self.accept(current, nxt, name)
                decisions.append(decision)
                if decision.accepted:
                    accepted = nxt
                    break
                if number >= c.max_iterations:
                    break
            if accepted is None:
                return LoopResult(iterations, diagnoses, decisions, "nothing improves")
            current = accepted
