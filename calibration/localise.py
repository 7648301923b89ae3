"""Where the model fails: residuals with their full noise, per-test shares, trends, conflicts.

Input is a ``Residuals`` record: measured and modelled values of every target at the optimum, the
noise of each, directly measured parameters (priors) as pseudo-observations, and the Jacobian of
the whitened residuals with respect to the free parameters. Output is a ``Localisation``: the
model-versus-measurement lack-of-fit test (weighted residual sum against its noise floor), each
test's share of the misfit with a Holm-corrected test, |r| > 2 flags, trend tests of the
residuals along the normal stress (E' log-log slope; shear-stress intercept and slope; dilatancy
slope), parameters pinned at a bound and priors pulled off their measured value.

Surrogate adequacy (curvature, confirmation) is not here on purpose: it says the response surface
is poor, not that physics is missing, and lives with the calibration (``calibration.analysis``'s surrogate check).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from . import stats
from .keys import ResponseKey
from .records import Noise

FLAG_LIMIT = 2.0
ALPHA = 0.05


@dataclass
class Residuals:
    """Whitened residuals (measured - model) / sd of targets, then of priors."""

    keys: list[ResponseKey]                  # one per target row
    measured: np.ndarray
    model: np.ndarray
    noise: list[Noise]
    prior_names: list[str]                   # one per prior row, after the targets
    prior_r: np.ndarray                      # (value - prior) / prior sd, sign as a residual: prior - value
    J: np.ndarray                            # d r / d (coded free parameter), rows = targets + priors
    free: list[str]
    absorbing: list[bool]                    # False: column dropped (parameter pinned, pushing outward)
    # the fitted surface's standard error of its mean prediction at the optimum, per target row (natural units;
    # 0 where the surface has no error estimate). Not part of the lack of fit, which compares batteries with
    # measurements; it moves the optimum the surfaces were searched for, so the intervals carry it.
    surface_se: np.ndarray | None = None
    # batteries at fresh seeds after a polish chose the point on others (``calibration.polish.hold_out``)
    held_out: bool = False

    @property
    def sd(self) -> np.ndarray:
        return np.array([n.sd for n in self.noise])

    @property
    def r_targets(self) -> np.ndarray:
        return (self.measured - self.model) / self.sd

    @property
    def r(self) -> np.ndarray:
        return np.concatenate([self.r_targets, self.prior_r])

    @property
    def df(self) -> np.ndarray:
        return np.concatenate([[n.df for n in self.noise], np.full(len(self.prior_names), math.inf)])

    @property
    def tests(self) -> list[str]:
        return [k.test for k in self.keys] + ["prior"] * len(self.prior_names)

    def M(self) -> np.ndarray:
        cols = [j for j, keep in enumerate(self.absorbing) if keep]
        return stats.residual_maker(self.J[:, cols])

    def chi2(self) -> float:
        r = self.r
        return float(r @ r)

    @property
    def judged(self) -> np.ndarray:
        """The residuals the lack of fit and the tests' own checks judge: ``r``, or, on held-out batteries, the
        part of it no parameter change absorbs (M r).

        Why: the tests' null, r ~ M z, holds for residuals at the least-squares point of their own batteries.
        At a point chosen on other batteries, r = M e_meas - eta_new + P eta_chosen (whitened; P = I - M): the
        parameters' error, carried by the chosen batteries' scatter, adds (I - M) components, and |r|^2 exceeds
        its n - p degrees of freedom by about twice p times the simulator's share of the variance (on the
        chaotic stand-in, a true model's false alarms rose from 5 % to 11 %). M r has covariance
        M (D_meas + D_sim) M = M whatever the shares: exactly the null the tests assume, and free of the
        choice's scatter, which lies along the Jacobian's columns to first order. It is |r + J du|^2 at the
        linearised best du on the held-out batteries: misfit that no parameter change would take away."""
        return self.M() @ self.r if self.held_out else self.r


@dataclass
class Localisation:
    lack_of_fit: stats.LackOfFit
    rows: list[dict]
    tests: list[dict]
    trends: dict[str, Any]
    conflicts: dict[str, list[dict]]
    reachability: list[dict] = field(default_factory=list)
    # the candidate effects' directed test, once the diagnosis has run their batteries (attribute.py)
    directed: stats.DirectedTest | None = None
    # the seeded null residuals the lack of fit was judged on; the directed test reuses them, so both
    # tests see the same null (max-T over the two is then one simulation)
    null_draws: np.ndarray | None = field(default=None, repr=False, compare=False)

    def with_directed(self, directed: stats.DirectedTest) -> "Localisation":
        """This localisation judged on both tests: the omnibus and the candidates' directed test."""
        return dataclasses.replace(self, directed=directed)

    @property
    def adequacy_p(self) -> float:
        """p of "the model reproduces the measurements": the omnibus lack of fit alone, or, once the
        diagnosis has tested the candidate effects, Holm over the omnibus and the directed test."""
        return stats.combined_p(self.lack_of_fit.p_value, None if self.directed is None else self.directed.p_value)

    @property
    def fails(self) -> bool:
        return self.adequacy_p < ALPHA

    @property
    def suspect(self) -> bool:
        """Signs of missing physics the omnibus test may not see: a parameter pinned at a bound of the
        user's box, a prior pulled off its measured value, a target no parameter set reaches. Reason to
        run the diagnosis (and its directed test) even when the lack of fit passes."""
        return bool(self.conflicts.get("active_bounds") or self.conflicts.get("priors_pulled")
                    or any(not r.get("reachable", True) for r in self.reachability))

    def to_dict(self) -> dict:
        return {"lack_of_fit": self.lack_of_fit.to_dict(), "fails": self.fails, "adequacy_p": self.adequacy_p,
                "directed": None if self.directed is None else self.directed.to_dict(), "suspect": self.suspect,
                "targets": self.rows, "tests": self.tests, "trends": self.trends, "conflicts": self.conflicts,
                "reachability": self.reachability}


def _trend_rows(res: Residuals, test: str, quantity: str, log: bool) -> tuple[np.ndarray, ...] | None:
    idx = [i for i, k in enumerate(res.keys)
           if k.test == test and k.quantity == quantity and k.stress_pa() is not None]
    if len({res.keys[i].stress_pa() for i in idx}) < 2:
        return None
    sigma = np.array([res.keys[i].stress_pa() for i in idx])
    meas, model, sd = res.measured[idx], res.model[idx], res.sd[idx]
    if log:
        if np.any(meas <= 0) or np.any(model <= 0):
            return None
        return np.log(sigma), np.log(meas / model), sd / meas, meas, model, sigma
    return sigma, meas - model, sd, meas, model, sigma


def trends(res: Residuals) -> dict[str, Any]:
    """Residual trends along the normal stress that turn 'E' grows with stress' or 'an unexplained
    intercept' into p-values."""
    out: dict[str, Any] = {}
    rows = _trend_rows(res, "cct", "confined_modulus_pa", log=True)
    if rows is not None:
        x, y, sd, meas, model, sigma = rows
        t = stats.weighted_trend(x, y, sd)
        slope_meas = stats.weighted_trend(x, np.log(meas), sd).slope
        slope_model = float(np.polyfit(x, np.log(model), 1)[0])
        out["modulus_log_slope"] = {
            "description": "slope of log(E' measured / E' model) against log(normal stress)",
            **t.to_dict(), "measured_slope": slope_meas, "model_slope": slope_model,
            "significant": t.p_slope < ALPHA}
    rows = _trend_rows(res, "dst", "residual_shear_stress_pa", log=False)
    if rows is not None:
        x, y, sd, meas, model, sigma = rows
        t = stats.weighted_trend(x, y, sd)
        fit_meas = stats.weighted_trend(x, meas, sd)
        fit_model = np.polyfit(x, model, 1)
        out["shear_stress"] = {
            "description": "residual shear stress (measured - model, Pa) against normal stress (Pa)",
            **t.to_dict(), "significant_slope": t.p_slope < ALPHA, "significant_intercept": t.p_intercept < ALPHA,
            "measured_cohesion_pa": fit_meas.intercept, "measured_cohesion_se_pa": fit_meas.intercept_se,
            "model_cohesion_pa": float(fit_model[1]),
            "measured_friction_angle_deg": math.degrees(math.atan(fit_meas.slope)),
            "model_friction_angle_deg": math.degrees(math.atan(fit_model[0]))}
    rows = _trend_rows(res, "dst", "dilatancy_angle_deg", log=False)
    if rows is not None:
        x, y, sd, *_ = rows
        t = stats.weighted_trend(x, y, sd)
        out["dilatancy"] = {"description": "dilatancy residual (deg) against normal stress (Pa)",
                            **t.to_dict(), "significant": t.p_slope < ALPHA}
    return out


def conflicts(active_bounds: list[dict], priors: list[dict]) -> dict[str, list[dict]]:
    """Parameters pinned at a bound (the direction they push) and priors pulled > 2 sd (G1)."""
    bounds = [{"parameter": b["parameter"], "side": b["side"], "value": b["value"],
               "pushes": "higher" if b["side"] == "high" else "lower",
               "meaning": f"the fit wants {b['parameter']} {'above' if b['side'] == 'high' else 'below'} "
                          "the range it may take: either the range is too narrow or the parameter is "
                          "compensating for missing physics"} for b in active_bounds]
    pulled = [{**p, "meaning": f"{p['parameter']} calibrates {abs(p['standardised_residual']):.1f} sd "
                              f"{'above' if p['standardised_residual'] > 0 else 'below'} its measured value"}
              for p in priors if abs(p["standardised_residual"]) > FLAG_LIMIT]
    return {"active_bounds": bounds, "priors_pulled": pulled}


def localise(res: Residuals, *, active_bounds=(), priors=(), reachability=(), seed: int = 0) -> Localisation:
    """The lack of fit, the tests' own checks and the rows a report shows. The rows keep the batteries' own
    residuals (``res.r``); the tests judge ``res.judged`` (the same, except on held-out batteries)."""
    raw, r, M, df = res.r, res.judged, res.M(), res.df
    draws = stats.null_residuals(M, df, seed=seed)
    lof = stats.lack_of_fit(r, M, df, draws=draws)
    rows = []
    for i, key in enumerate(res.keys):
        rows.append({"test": key.test, "quantity": key.quantity, "condition": key.condition_dict,
                     "label": key.label, "measured": float(res.measured[i]), "model": float(res.model[i]),
                     "residual": float(res.measured[i] - res.model[i]), "standardised_residual": float(raw[i]),
                     "flagged": bool(abs(raw[i]) > FLAG_LIMIT), "noise": res.noise[i].to_dict()})
    for j, name in enumerate(res.prior_names):
        i = len(res.keys) + j
        rows.append({"test": "prior", "quantity": name, "condition": {}, "label": f"prior on {name}",
                     "standardised_residual": float(raw[i]), "flagged": bool(abs(raw[i]) > FLAG_LIMIT)})
    total = float(r @ r)
    tests = []
    names = res.tests
    groups = list(dict.fromkeys(names))
    pvals = []
    # the noise alone, nothing fitted: a test within its own measurements' noise never fails (own_check_pvalue)
    unfitted = stats.null_residuals(np.eye(r.size), df, seed=seed)
    for test in groups:
        members = np.array([i for i, t in enumerate(names) if t == test])
        pvals.append(stats.own_check_pvalue(r, members, M, draws, unfitted))
        chi2 = float(np.sum(r[members] ** 2))
        tests.append({"test": test, "n": int(members.size), "chi2": chi2,
                      "share": chi2 / total if total > 0 else 0.0, "p_value": pvals[-1]})
    for row, adj in zip(tests, stats.holm(pvals)):
        row["p_holm"] = float(adj)
        row["fails"] = bool(adj < ALPHA)
    return Localisation(lof, rows, tests, trends(res), conflicts(list(active_bounds), list(priors)),
                        list(reachability), null_draws=draws)
