"""Calibration of one design: optimum through doe.optimise, confirmation batteries, residuals.

The fitted response surfaces give the optimum theta*; batteries at theta* with a few seeds (the
confirmation) give the model's actual values there. Whether they miss the surfaces is judged in one
place, doe.confirm's prediction intervals (``calibration.analysis``'s surrogate check): a miss is
fixed on the batteries (``calibration.polish``) or by a narrower or composite design, never blamed
on physics.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from doe.designs import Design
from doe.constraints import Target
from doe.factors import DoeError
from doe.optimise import CalibrationResult, calibrate

from .fitting import TargetModel, run_values
from .keys import ResponseKey, find
from .localise import Residuals
from .records import Noise, VarianceTerm, measurement_variances

# coded step of the central differences on the fitted polynomials (exact for quadratics)
_FD_STEP = 1e-3


def generators_for(k: int) -> list[str] | None:
    """Half fraction of highest resolution: 2^(4-1) IV (D=ABC, the thesis's Table A.8), 2^(5-1) V..."""
    if k <= 3:
        return None
    letters = "ABCDEFGHJKLMNOPQRSTUVWXYZ"[:k]
    return [f"{letters[-1]}={letters[:-1]}"]


def target_variances(targets: Sequence, default_relative: float, discrepancy: Sequence = ()) -> dict:
    """Each target's variance: the measurement's (``records.measurement_variances``) plus its test's
    model-form discrepancy (``calibration.discrepancy``): the one noise model the optimum, the report, the
    lack of fit and the diagnosis share."""
    from .discrepancy import with_discrepancy

    targets = list(targets)
    return with_discrepancy(measurement_variances(targets, default_relative), {t.key: t.mean for t in targets},
                            discrepancy)


def doe_targets(models: Sequence[TargetModel], default_relative: float, discrepancy: Sequence = ()) -> list[Target]:
    out = []
    variances = target_variances([m.target for m in models], default_relative, discrepancy)
    for m in models:
        if m.fit is None:
            continue
        u = math.sqrt(variances[m.target.key].variance)
        out.append(Target(m.key.name, m.target.mean, u, m.key.test, m.key.label))
    return out


def optimum(models: Sequence[TargetModel], *, default_relative: float, priors=(), constraints=(), fixed=None,
            seed: int = 0, bounds=None, n_starts: int = 6, allow_extrapolation: bool = False,
            discrepancy: Sequence = ()) -> CalibrationResult:
    fits = {m.key.name: m.fit for m in models if m.fit is not None}
    targets = doe_targets(models, default_relative, discrepancy)
    if not targets:
        raise DoeError("no target could be modelled")
    return calibrate(fits, targets, priors=list(priors), constraints=list(constraints), fixed=fixed,
                     seed=seed, bounds=bounds, n_starts=n_starts, allow_extrapolation=allow_extrapolation)


def coded_gradient(fit, design: Design, parameters: dict[str, float], free: Sequence[str]) -> np.ndarray:
    """d prediction / d coded factor at ``parameters``, for the ``free`` factors (central differences)."""
    names = design.names
    u0 = np.array([float(design.factor(n).to_coded(parameters[n])) for n in names])
    cols = [names.index(n) for n in free]
    points = np.repeat(u0[None, :], 2 * len(cols), axis=0)
    for j, i in enumerate(cols):
        points[2 * j, i] += _FD_STEP
        points[2 * j + 1, i] -= _FD_STEP
    values = fit.predict_coded(points)
    return (values[0::2] - values[1::2]) / (2 * _FD_STEP)


@dataclass
class Confirmation:
    """Batteries at theta*: their mean per target and the pooled seed-to-seed scatter."""

    seeds: list[int]
    runs: list[list[dict]]
    mean: dict[ResponseKey, float] = field(default_factory=dict)
    sim_sd: dict[ResponseKey, float] = field(default_factory=dict)
    sim_df: dict[ResponseKey, int] = field(default_factory=dict)


def confirm(models: Sequence[TargetModel], runs: list[list[dict]], seeds: list[int]) -> Confirmation:
    """Mean of the batteries at theta* per target, and the simulator's seed-to-seed scatter.

    The scatter pools the centre replicates' pure error with the confirmation replicates, and,
    like the measurement scatter (``records.measurement_variances``), pools the conditions of one
    (test, quantity) family on a relative scale (absolute for angles): one packing's randomness
    moves E' at every stress alike, and 2-3 degrees of freedom per target would give t tails.
    """
    conf = Confirmation(list(seeds), runs)
    values = [run_values(r) for r in runs]
    family: dict[tuple[str, str], list[float]] = {}
    members: dict[tuple[str, str], list[ResponseKey]] = {}
    for m in models:
        if m.key is None:
            continue
        key = find(values[0].keys(), m.key)
        if key is None:
            continue
        ys = np.array([v.get(key, math.nan) for v in values])
        mean = float(np.mean(ys))
        conf.mean[m.key] = mean
        relative = not m.key.quantity.endswith("_deg")
        scale = abs(mean) if relative and mean != 0 else 1.0
        ss, df = 0.0, 0
        if m.pure_error_sd is not None and m.pure_error_df > 0:
            ss, df = m.pure_error_sd**2 * m.pure_error_df, m.pure_error_df
        if ys.size >= 2:
            ss += float(np.sum((ys - ys.mean()) ** 2))
            df += ys.size - 1
        fam = (m.key.test, m.key.quantity)
        acc = family.setdefault(fam, [0.0, 0])
        acc[0] += ss / scale**2
        acc[1] += df
        members.setdefault(fam, []).append(m.key)
    for fam, keys in members.items():
        ss, df = family[fam]
        if df <= 0 or ss <= 0:
            continue
        for key in keys:
            relative = not key.quantity.endswith("_deg")
            scale = abs(conf.mean[key]) if relative and conf.mean[key] != 0 else 1.0
            conf.sim_sd[key], conf.sim_df[key] = math.sqrt(ss / df) * scale, df
    return conf


def natural_per_coded(factor, value: float) -> float:
    """d natural / d coded of a factor at ``value`` (log factors: proportional to the value)."""
    if factor.log:
        return math.log(10.0) * value * factor.half_range_t
    return factor.half_range_t


def active_bounds(design: Design, theta: dict[str, float], box: dict | None = None, tol: float = 1e-6) -> list[dict]:
    """Factors of ``theta`` sitting on a bound of ``box`` ({name: (low, high)}; default the design's)."""
    out = []
    for f in design.factors:
        low, high = (box or {}).get(f.name, (f.low, f.high))
        span = abs(high - low) or 1.0
        if theta[f.name] <= low + tol * span:
            out.append({"parameter": f.name, "side": "low", "value": theta[f.name]})
        elif theta[f.name] >= high - tol * span:
            out.append({"parameter": f.name, "side": "high", "value": theta[f.name]})
    return out


def prior_rows(priors: Sequence[dict], theta: dict[str, float]) -> list[dict]:
    return [{"parameter": p["parameter"], "value": p["value"], "uncertainty": p["uncertainty"],
             "source": p.get("source", ""),
             "standardised_residual": (theta[p["parameter"]] - p["value"]) / p["uncertainty"]}
            for p in priors]


def gauss_newton_step(design: Design, residuals, theta: dict[str, float]) -> np.ndarray:
    """Coded step minimising |r + J du| with theta + du inside the box (scipy's bounded least squares)."""
    from scipy.optimize import lsq_linear

    u = np.array([float(design.factor(n).to_coded(theta[n])) for n in residuals.free])
    sol = lsq_linear(residuals.J, -residuals.r, bounds=(-1.0 - u, 1.0 - u))
    return sol.x


def move(design: Design, theta: dict[str, float], free: Sequence[str], du: np.ndarray) -> dict[str, float]:
    out = dict(theta)
    for name, d in zip(free, du):
        f = design.factor(name)
        out[name] = float(f.to_natural(float(np.clip(float(f.to_coded(theta[name])) + d, -1.0, 1.0))))
    return out


def residuals_at(design: Design, models: Sequence[TargetModel], theta: dict[str, float], conf: Confirmation,
                 priors: Sequence[dict], default_relative: float, discrepancy: Sequence = ()) -> Residuals:
    """Whitened residuals of the confirmation batteries at ``theta`` against the measurements, the
    priors as pseudo-observations, and the Jacobian from the fitted surfaces (coded units).

    A parameter pinned at a bound of the box with the misfit pushing it outward cannot absorb
    anything more in that direction (friction saturating at its ceiling): its column is marked
    not absorbing, so the diagnosis does not project the missing effect away with it.
    """
    free = list(design.names)
    keys, measured, model, noise, rows, surface_se = [], [], [], [], [], []
    m = len(conf.seeds)
    variances = target_variances([tm.target for tm in models], default_relative, discrepancy)
    for tm in models:
        if tm.fit is None or tm.key not in conf.mean:
            continue
        meas = variances[tm.target.key]
        sim_sd = conf.sim_sd.get(tm.key, 0.0)
        sim = VarianceTerm(sim_sd**2 / m, conf.sim_df.get(tm.key, math.inf), "centre and confirmation replicates")
        n = Noise(meas, sim)
        keys.append(tm.target.key)
        measured.append(tm.target.mean)
        model.append(conf.mean[tm.key])
        noise.append(n)
        rows.append(-coded_gradient(tm.fit, design, theta, free) / n.sd)
        surface_se.append(surface_standard_error(tm.fit, theta))
    prior_names, prior_r = [], []
    for p in priors:
        f = design.factor(p["parameter"])
        prior_names.append(p["parameter"])
        prior_r.append((p["value"] - theta[p["parameter"]]) / p["uncertainty"])
        g = np.zeros(len(free))
        g[free.index(p["parameter"])] = -natural_per_coded(f, theta[p["parameter"]]) / p["uncertainty"]
        rows.append(g)
    J = np.array(rows).reshape(len(rows), len(free))
    r = np.concatenate([(np.array(measured) - np.array(model)) / np.array([x.sd for x in noise]), prior_r])
    grad_s = 2.0 * J.T @ r          # d(sum r^2)/du
    pinned = {b["parameter"]: b["side"] for b in active_bounds(design, theta)}
    absorbing = []
    for j, name in enumerate(free):
        side = pinned.get(name)
        outward = (side == "high" and grad_s[j] < 0) or (side == "low" and grad_s[j] > 0)
        absorbing.append(not outward)
    return Residuals(keys, np.array(measured), np.array(model), noise, prior_names, np.array(prior_r),
                     J, free, absorbing, np.array(surface_se, float))


def measurement_led(res: Residuals) -> list[str]:
    """The measured parameters (the priors' rows of ``res``) that their own measurement pins more tightly than
    the targets do: the prior's information (its row of J squared, coded units) above the targets' marginal
    information about the parameter, what is left of J_t^T J_t on its diagonal once the other free parameters
    have traded against it (the Schur complement). A parameter on a valley the targets cannot resolve (two
    frictions that trade) has little of the latter, so its measurement is the better evidence; one a target
    fixes (particle density through a bulk density measured to a fraction of a percent) is led by that target,
    and holding it at a coarser measurement would throw the target's evidence away."""
    n_targets = len(res.keys)
    info = res.J[:n_targets].T @ res.J[:n_targets]
    out = []
    for name, row in zip(res.prior_names, res.J[n_targets:]):
        j = res.free.index(name)
        others = [k for k in range(len(res.free)) if k != j]
        marginal = info[j, j]
        if others:
            cross = info[j, others]
            marginal -= float(cross @ np.linalg.pinv(info[np.ix_(others, others)]) @ cross)
        if row[j] ** 2 > marginal and name not in out:
            out.append(name)
    return out


def surface_standard_error(fit, theta: dict[str, float]) -> float:
    """The standard error of the surface's mean prediction at ``theta`` (doe's se_mean: x^T cov(beta) x), 0 when
    the surface has no residual degrees of freedom to estimate it from (a saturated fit)."""
    se = fit.predict([{n: theta[n] for n in fit.design.names}])[0]["se_mean"]
    return float(se) if se is not None and math.isfinite(se) else 0.0
