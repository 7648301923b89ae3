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
    notes: list[str] = field(default_factory=list)

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
        parts += self.notes
        return "\n\n".join(parts)


def _factor_table(models) -> dict[str, Factor]:
    out: dict[str, Factor] = {}
    for m in models.values():
        for f in m.design.factors:
            out.setdefault(f.name, f)
    return out


class _Problem:
    """Free coded variables u -> natural parameters, residuals and their exact Jacobian.

    The models are polynomials in coded units, so values and gradients are evaluated
    directly from exponent matrices: no finite differences, which keeps a
    multi-start calibration well under a second.
    """

    def __init__(self, models, factors, free, fixed, lo, hi):
        self.models, self.factors, self.free, self.fixed = models, factors, free, fixed
        self.lo, self.hi = lo, hi
        self.names = list(factors)
        self.free_idx = np.array([self.names.index(n) for n in free], dtype=int)
        self.base = np.array([float(factors[n].to_coded(fixed[n])) if n in fixed else 0.0 for n in self.names])
        self.compiled = {}
        for key, m in models.items():
            idx, a, b = [], [], []
            for f in m.design.factors:
                g = factors[f.name]
                if g.log != f.log:
                    raise DoeError(f"models disagree on whether {f.name} is on a log scale")
                idx.append(self.names.index(f.name))
                a.append(g.half_range_t / f.half_range_t)
                b.append((g.centre_t - f.centre_t) / f.half_range_t)
            E = np.array([(0,) * m.design.k] + [tuple(t) for t in m.terms], dtype=float)
            self.compiled[key] = (np.array(idx), np.array(a), np.array(b), E, np.asarray(m.params, float),
                                  getattr(m, "transform", "none") == "log")

    def coded_all(self, u) -> np.ndarray:
        x = self.base.copy()
        x[self.free_idx] = u
        return x

    def natural(self, u) -> dict[str, float]:
        p = dict(self.fixed)
        for name, ui in zip(self.free, u):
            p[name] = float(self.factors[name].to_natural(float(ui)))
        return p

    def dnatural_du(self, u) -> np.ndarray:
        out = []
        for name, ui in zip(self.free, u):
            f = self.factors[name]
            x = float(f.to_natural(float(ui)))
            out.append(math.log(10.0) * x * f.half_range_t if f.log else f.half_range_t)
        return np.array(out)

    def value_grad(self, key, u) -> tuple[float, np.ndarray]:
        idx, a, b, E, beta, log_scale = self.compiled[key]
        xm = a * self.coded_all(u)[idx] + b
        P = xm[None, :] ** E
        val = float(beta @ np.prod(P, axis=1))
        # d/dx_j of each monomial: its exponent times x_j^(e-1), times the product of the other
        # factors' powers (prefix x suffix products, so no division by a zero coordinate)
        ones = np.ones((P.shape[0], 1))
        prefix = np.cumprod(np.hstack([ones, P[:, :-1]]), axis=1)
        suffix = np.cumprod(np.hstack([ones, P[:, :0:-1]]), axis=1)[:, ::-1]
        dP = np.where(E > 0, E * xm[None, :] ** np.maximum(E - 1, 0), 0.0)
        g = a * (beta @ (dP * prefix * suffix))
        if log_scale:  # a surface of ln(y): y = exp(polynomial), dy = y d(polynomial)
            val = math.exp(val)
            g = val * g
        g_all = np.zeros(len(self.names))
        np.add.at(g_all, idx, g)
        return val, g_all[self.free_idx]

    def predict(self, key, params: dict[str, float]) -> float:
        u = np.array([float(self.factors[n].to_coded(params[n])) for n in self.free])
        return self.value_grad(key, u)[0]


def _solve(fun, prob: _Problem, cons, starts, method) -> tuple[np.ndarray, float, bool, str]:
    best = None
    bounds = list(zip(prob.lo, prob.hi))
    for x0 in starts:
        if method == "trust-constr":
            from scipy.optimize import NonlinearConstraint as SciNC
            sc = [SciNC(lambda u, c=c: c["fun"](u), 0, np.inf) for c in cons]
            r = minimize(fun, x0, jac=True, method="trust-constr", bounds=bounds, constraints=sc,
                         options={"maxiter": 500, "gtol": 1e-10, "xtol": 1e-10})
        else:
            r = minimize(fun, x0, jac=True, method="SLSQP", bounds=bounds, constraints=cons,
                         options={"maxiter": 300, "ftol": 1e-12})
        x = np.clip(r.x, prob.lo, prob.hi)
        viol = max([0.0] + [-c["fun"](x) for c in cons])
        feasible = viol <= _FEAS_TOL
        val = float(fun(x)[0])
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

    prior_pos = [free.index(q.parameter) if q.parameter in free else -1 for q in priors]

    def residuals_jac(u) -> tuple[np.ndarray, np.ndarray]:
        """Standardised residuals and their Jacobian with respect to u."""
        rows, jac = [], []
        for t in targets:
            v, g = prob.value_grad(t.response, u)
            rows.append((v - t.value) / t.uncertainty)
            jac.append(g / t.uncertainty)
        if priors:
            p, dn = prob.natural(u), prob.dnatural_du(u)
            for q, j in zip(priors, prior_pos):
                rows.append((p[q.parameter] - q.value) / q.uncertainty)
                g = np.zeros(len(free))
                if j >= 0:
                    g[j] = dn[j] / q.uncertainty
                jac.append(g)
        return np.array(rows), np.array(jac).reshape(len(rows), len(free))

    def objective(u):
        r, J = residuals_jac(u)
        return float(r @ r), 2.0 * J.T @ r

    cons = []
    for c in constraints:
        jac = None
        if hasattr(c, "coefficients"):
            w = np.array([c.coefficients.get(n, 0.0) for n in free])
            def jac(u, w=w):
                return w * prob.dnatural_du(u)
        if math.isfinite(c.upper):
            cons.append({"type": "ineq", "fun": lambda u, c=c: c.upper - c.value(prob.natural(u))})
            if jac is not None:
                cons[-1]["jac"] = lambda u, jac=jac: -jac(u)
        if math.isfinite(c.lower):
            cons.append({"type": "ineq", "fun": lambda u, c=c: c.value(prob.natural(u)) - c.lower})
            if jac is not None:
                cons[-1]["jac"] = jac
    rng = np.random.default_rng(seed)
    starts = [np.clip(np.zeros(len(free)), prob.lo, prob.hi)]
    starts += [rng.uniform(prob.lo, prob.hi) for _ in range(max(n_starts, 1) - 1)]
    u, val, feasible, msg = _solve(objective, prob, cons, starts, method)
    params = prob.natural(u)

    # parameter uncertainty from the Gauss-Newton curvature of S in natural units
    J = residuals_jac(u)[1] / prob.dnatural_du(u)[None, :]
    std: dict[str, float | None] = {n: None for n in free}
    notes = []
    JtJ = J.T @ J
    if np.linalg.matrix_rank(JtJ) == len(free):
        cov = np.linalg.inv(JtJ)
        std = {n: float(math.sqrt(max(cov[j, j], 0.0))) for j, n in enumerate(free)}
    else:
        notes.append(f"{len(targets)} target(s) and {len(priors)} prior(s) do not identify all {len(free)} free "
                     "parameters at the optimum: many parameter sets fit equally well, so no standard deviations; "
                     "add targets or priors, or fix parameters")
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
            v, g = prob.value_grad(t.response, uu)
            r = (v - t.value) / t.uncertainty
            return r * r, 2.0 * r * g / t.uncertainty
        rs = [np.clip(np.zeros(len(free)), prob.lo, prob.hi)]
        rs += [np.random.default_rng([seed, i]).uniform(prob.lo, prob.hi) for _ in range(n_reach - 1)]
        ur, vr, _, _ = _solve(single, prob, cons, rs, method)
        zmin = math.sqrt(max(vr, 0.0))
        reach.append({"response": t.response, "test": t.test, "condition": t.condition, "target": t.value,
                      "min_standardised_misfit": zmin, "reachable": zmin <= reach_threshold,
                      "closest_prediction": prob.value_grad(t.response, ur)[0],
                      "closest_parameters": prob.natural(ur)})
    message = msg if feasible else f"no feasible point found ({msg})"
    return CalibrationResult(params, std, {n: float(x) for n, x in zip(free, u)}, val, target_rows, prior_rows,
                             active_bounds, active, cons_rows, reach, bool(feasible), message, fixed,
                             allow_extrapolation, seed, len(starts), notes)
