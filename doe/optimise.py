"""Calibration: micro parameters that make the fitted models match measured targets.

Minimises S(x) = sum_t ((yhat_t(x) - y_t) / u_t)^2 + sum_p ((x_p - m_p) / s_p)^2,
the uncertainty-weighted sum of squared residuals with measured parameters as
Gaussian priors, over the design box (the models are not to be trusted outside
it) subject to linear and non-linear constraints. The search runs in coded
units with SLSQP from several seeded starts, so the same seed gives the same
answer. Reachability asks, per target alone, how close any admissible parameter
set can get: a target more than 3 standard uncertainties away from everything
the box can produce is out of reach, and no amount of optimisation will fix it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import minimize

from .constraints import Prior, Target, as_constraint
from .factors import DoeError, Factor
from .fit import ResponseFit

_FEAS_TOL = 1e-6


@dataclass
class CalibrationResult:
    parameters: dict[str, float]
    parameter_std: dict[str, float | None]
    coded: dict[str, float]
    objective: float
    targets: list[dict]
    priors: list[dict]
    active_bounds: list[dict]
    active_constraints: list[str]
    constraints: list[dict]
    reachability: list[dict]
    success: bool
    message: str
    fixed: dict[str, float] = field(default_factory=dict)
    allow_extrapolation: bool = False
    seed: int = 0
    n_starts: int = 0

    @property
    def unreachable(self) -> list[dict]:
        return [r for r in self.reachability if not r["reachable"]]

    def to_dict(self) -> dict:
        return {k: v for k, v in self.__dict__.items()}

    def summary(self) -> str:
        from .report import fmt, table
        rows = [[n, v, self.parameter_std.get(n), "fixed" if n in self.fixed else ""]
                for n, v in self.parameters.items()]
        parts = [f"Calibration {'converged' if self.success else 'FAILED'}: {self.message}; "
                 f"weighted SSR {fmt(self.objective)}",
                 table(["Parameter", "Optimum", "Std", ""], rows)]
        parts.append(table(["Response", "Test", "Condition", "Target", "Uncert.", "Predicted", "PI low", "PI high",
                            "z"], [[t["response"], t["test"], t["condition"], t["target"], t["uncertainty"],
                                    t["predicted"], t["pi_low"], t["pi_high"], t["standardised_residual"]]
                                   for t in self.targets]))
        parts.append(table(["Response", "Test", "Condition", "Min |z| in box", "Reachable"],
                           [[r["response"], r["test"], r["condition"], r["min_standardised_misfit"],
                             r["reachable"]] for r in self.reachability]))
        if self.active_bounds:
            parts.append("Active bounds: " + ", ".join(f"{b['parameter']} at {b['side']}" for b in self.active_bounds))
        if self.active_constraints:
            parts.append("Active constraints: " + ", ".join(self.active_constraints))
        return "\n\n".join(parts)


def _factor_table(models) -> dict[str, Factor]:
    out: dict[str, Factor] = {}
    for m in models.values():
        for f in m.design.factors:
            out.setdefault(f.name, f)
    return out


class _Problem:
    """Maps free coded variables to natural parameters and model predictions."""

    def __init__(self, models, factors, free, fixed, lo, hi):
        self.models, self.factors, self.free, self.fixed = models, factors, free, fixed
        self.lo, self.hi = lo, hi
        self.maps = {name: [m.design.factors[j] for j in range(m.design.k)] for name, m in models.items()}

    def natural(self, u) -> dict[str, float]:
        p = dict(self.fixed)
        for name, ui in zip(self.free, u):
            p[name] = float(self.factors[name].to_natural(ui))
        return p

    def predict(self, response: str, params: dict[str, float]) -> float:
        facs = self.maps[response]
        coded = np.array([[f.to_coded(params[f.name]) for f in facs]])
        return float(self.models[response].predict_coded(coded)[0])


def _solve(fun, prob: _Problem, cons, starts, method) -> tuple[np.ndarray, float, bool, str]:
    best = None
    bounds = list(zip(prob.lo, prob.hi))
    for x0 in starts:
        if method == "trust-constr":
            from scipy.optimize import NonlinearConstraint as SciNC
            sc = [SciNC(lambda u, c=c: c["fun"](u), 0, np.inf) for c in cons]
            r = minimize(fun, x0, method="trust-constr", bounds=bounds, constraints=sc,
                         options={"maxiter": 500, "gtol": 1e-10, "xtol": 1e-10})
        else:
            r = minimize(fun, x0, method="SLSQP", bounds=bounds, constraints=cons,
                         options={"maxiter": 300, "ftol": 1e-12})
        x = np.clip(r.x, prob.lo, prob.hi)
        viol = max([0.0] + [-c["fun"](x) for c in cons])
        feasible = viol <= _FEAS_TOL
        val = float(fun(x))
        key = (not feasible, val)
        if best is None or key < best[0]:
            best = (key, x, val, feasible, str(r.message))
    _, x, val, feasible, msg = best
    return x, val, feasible, msg


def calibrate(models, targets, *, bounds=None, fixed=None, constraints=(), priors=(),
              allow_extrapolation: bool = False, n_starts: int = 8, seed: int = 0,
              method: str = "SLSQP", reach_threshold: float = 3.0, alpha: float = 0.05) -> CalibrationResult:
    """Find parameters minimising the uncertainty-weighted SSR of `targets`.

    models: {response: ResponseFit} (or a list of fits); targets: Target objects or
    dicts {response, value, uncertainty, test, condition}; bounds: {name: (low, high)}
    in natural units, inside the design box unless allow_extrapolation; fixed:
    {name: value}; constraints: LinearConstraint / NonlinearConstraint / text such as
    'friction_pw <= friction_pp'; priors: Prior objects or dicts {parameter, value, uncertainty}.
    """
    if isinstance(models, (list, tuple)):
        models = {m.response: m for m in models}
    if not models:
        raise DoeError("no fitted models given")
    targets = [t if isinstance(t, Target) else Target.from_dict(t) for t in targets]
    priors = [p if isinstance(p, Prior) else Prior.from_dict(p) for p in priors]
    constraints = [as_constraint(c) for c in constraints]
    if not targets:
        raise DoeError("no targets given")
    if method not in ("SLSQP", "trust-constr"):
        raise DoeError("method must be 'SLSQP' or 'trust-constr'")
    for t in targets:
        if t.response not in models:
            raise DoeError(f"target {t.response!r} has no fitted model (models: {', '.join(models)})")
    factors = _factor_table(models)
    fixed = {k: float(v) for k, v in (fixed or {}).items()}
    bounds = dict(bounds or {})
    for name in list(fixed) + list(bounds) + [p.parameter for p in priors]:
        if name not in factors:
            raise DoeError(f"unknown parameter {name!r} (factors: {', '.join(factors)})")
    for c in constraints:
        for name in getattr(c, "parameters", []):
            if name not in factors:
                raise DoeError(f"constraint {c.name!r}: unknown parameter {name!r}")
    free = [n for n in factors if n not in fixed]
    if not free:
        raise DoeError("every parameter is fixed; nothing to calibrate")

    def box_check(name, lo, hi):
        f = factors[name]
        if not allow_extrapolation and (lo < f.low - 1e-12 * abs(f.low) or hi > f.high + 1e-12 * abs(f.high)):
            raise DoeError(f"{name} range [{lo:g}, {hi:g}] leaves the design region [{f.low:g}, {f.high:g}]; "
                           "pass allow_extrapolation=True to search outside it")
    for name, v in fixed.items():
        box_check(name, v, v)
    lo_c, hi_c = [], []
    for name in free:
        f = factors[name]
        lo, hi = bounds.get(name, (f.low, f.high))
        lo, hi = float(lo), float(hi)
        if not lo <= hi:
            raise DoeError(f"bounds for {name}: low {lo:g} exceeds high {hi:g}")
        box_check(name, lo, hi)
        lo_c.append(float(f.to_coded(lo)))
        hi_c.append(float(f.to_coded(hi)))
    prob = _Problem(models, factors, free, fixed, np.array(lo_c), np.array(hi_c))

    def residuals(u) -> np.ndarray:
        p = prob.natural(u)
        r = [(prob.predict(t.response, p) - t.value) / t.uncertainty for t in targets]
        r += [(p[q.parameter] - q.value) / q.uncertainty for q in priors]
        return np.array(r)

    def objective(u) -> float:
        r = residuals(u)
        return float(r @ r)

    cons = []
    for c in constraints:
        if math.isfinite(c.upper):
            cons.append({"type": "ineq", "fun": lambda u, c=c: c.upper - c.value(prob.natural(u))})
        if math.isfinite(c.lower):
            cons.append({"type": "ineq", "fun": lambda u, c=c: c.value(prob.natural(u)) - c.lower})
    rng = np.random.default_rng(seed)
    starts = [np.clip(np.zeros(len(free)), prob.lo, prob.hi)]
    starts += [rng.uniform(prob.lo, prob.hi) for _ in range(max(n_starts, 1) - 1)]
    u, val, feasible, msg = _solve(objective, prob, cons, starts, method)
    params = prob.natural(u)

    # parameter uncertainty from the Gauss-Newton curvature of S in natural units
    J = np.empty((len(targets) + len(priors), len(free)))
    for j, name in enumerate(free):
        h = 1e-5 * (prob.hi[j] - prob.lo[j] if prob.hi[j] > prob.lo[j] else 1.0)
        up, dn = u.copy(), u.copy()
        up[j] += h
        dn[j] -= h
        dx = float(factors[name].to_natural(up[j]) - factors[name].to_natural(dn[j]))
        J[:, j] = (residuals(up) - residuals(dn)) / dx
    std: dict[str, float | None] = {n: None for n in free}
    JtJ = J.T @ J
    if np.linalg.matrix_rank(JtJ) == len(free):
        cov = np.linalg.inv(JtJ)
        std = {n: float(math.sqrt(max(cov[j, j], 0.0))) for j, n in enumerate(free)}
    std.update({n: 0.0 for n in fixed})

    target_rows = []
    for t in targets:
        pred = models[t.response].predict([params], alpha)[0]
        z = (pred["mean"] - t.value) / t.uncertainty
        target_rows.append({"response": t.response, "test": t.test, "condition": t.condition,
                            "target": t.value, "uncertainty": t.uncertainty, "predicted": pred["mean"],
                            "pi_low": pred["pi_low"], "pi_high": pred["pi_high"], "ci_low": pred["ci_low"],
                            "ci_high": pred["ci_high"], "standardised_residual": z})
    prior_rows = [{"parameter": q.parameter, "value": q.value, "uncertainty": q.uncertainty, "source": q.source,
                   "standardised_residual": (params[q.parameter] - q.value) / q.uncertainty} for q in priors]
    active_bounds = []
    for j, name in enumerate(free):
        tol = 1e-6 * max(prob.hi[j] - prob.lo[j], 1e-12)
        if u[j] <= prob.lo[j] + tol:
            active_bounds.append({"parameter": name, "side": "low", "value": params[name]})
        elif u[j] >= prob.hi[j] - tol:
            active_bounds.append({"parameter": name, "side": "high", "value": params[name]})
    active, cons_rows = [], []
    for c in constraints:
        g = c.value(params)
        scale = 1.0
        if hasattr(c, "coefficients"):
            scale = sum(abs(v) * (factors[n].high - factors[n].low) for n, v in c.coefficients.items())
        tol = 1e-6 * max(scale, 1e-12)
        is_active = (math.isfinite(c.upper) and g >= c.upper - tol) or (math.isfinite(c.lower) and g <= c.lower + tol)
        if is_active:
            active.append(c.name)
        cons_rows.append({**c.to_dict(), "value_at_optimum": g, "active": bool(is_active)})

    reach = []
    n_reach = max(3, n_starts // 2)
    for i, t in enumerate(targets):
        def single(uu, t=t):
            return ((prob.predict(t.response, prob.natural(uu)) - t.value) / t.uncertainty) ** 2
        rs = [np.clip(np.zeros(len(free)), prob.lo, prob.hi)]
        rs += [np.random.default_rng([seed, i]).uniform(prob.lo, prob.hi) for _ in range(n_reach - 1)]
        ur, vr, _, _ = _solve(single, prob, cons, rs, method)
        zmin = math.sqrt(max(vr, 0.0))
        reach.append({"response": t.response, "test": t.test, "condition": t.condition, "target": t.value,
                      "min_standardised_misfit": zmin, "reachable": zmin <= reach_threshold,
                      "closest_prediction": prob.predict(t.response, prob.natural(ur)),
                      "closest_parameters": prob.natural(ur)})
    message = msg if feasible else f"no feasible point found ({msg})"
    return CalibrationResult(params, std, {n: float(x) for n, x in zip(free, u)}, val, target_rows, prior_rows,
                             active_bounds, active, cons_rows, reach, bool(feasible), message, fixed,
                             allow_extrapolation, seed, len(starts))
