"""Intervals on the calibrated parameters that say what the data fix and what they do not.

The optimiser's standard deviations (``doe.optimise``: Gauss-Newton on the targets' measurement
uncertainty alone) leave out the simulator's scatter in the confirmation batteries, any model-form
discrepancy and the model's own misfit, and they print one optimum for parameters that trade. Here the
covariance is built from the localisation's whitened Jacobian (``calibrate.residuals_at``), whose rows are
divided by each target's full noise (measurement, discrepancy, simulator over the confirmation seeds) and
include the priors, so

    cov(u) = s^2 (J^T J)^-1          (coded units; natural = coded x d natural / d coded)

with s^2 = 1 while the lack of fit passes, and s^2 = chi2 / dof (Birge's ratio) when it fails: a model that
misses the measurements by more than their noise cannot know its parameters better than that misfit
allows, and the intervals widen with it (the t quantile on the lack of fit's dof then replaces the normal).
A model-form discrepancy (``calibration.discrepancy``) is not noise that averages out across a test's rows:
whatever makes another engine's E' 12 % higher does so at every stress window alike. The fit weights each
row by its full variance as if the rows were independent; the discrepancy is taken as one level shift per
(test, quantity), shared by that quantity's rows (correlation 1, Kennedy & O'Hagan's discrepancy at its
longest correlation length), and the covariance of the estimator so weighted is the sandwich

    cov(u) = A^-1 J^T (I + C) J A^-1 = A^-1 + A^-1 J^T C J A^-1,   A = J^T J,

where C holds the whitened discrepancy's covariances between different rows of one quantity (the diagonal
is already in the weights). Without a discrepancy C = 0 and this is the plain inverse above: four E' windows
then no longer count as four independent views of the stiffness when they share one model-form error.
A lack of fit that passes does not prove the model exact: it rules out only the model-form errors it would see.
A shift shared by one quantity's rows that the parameters absorb is invisible to it at any size, and it is what
moves them (tier A's worlds, whose closed forms stray 2 % from the model's, put particle density 3-5 sd off while
the test passed). So every quantity carries, beyond what the weights hold (noise, simulator, a stated
discrepancy), the shared shift the test detects only half the time: in whitened units k = sqrt(lambda_50 / n),
with n the quantity's rows and lambda_50 the non-centrality at which chi2'(dof, lambda) exceeds the test's
critical value with probability 1/2 (median power, on the lack of fit's own dof and ALPHA). It enters C with its
diagonal (the weights do not hold it). No constant is chosen: the allowance follows from the test's dof and
level, and it shrinks as a quantity is measured on more rows.
The optimum itself was searched for on the fitted response surfaces, so their error moves it as the measurements'
noise does: at the optimum, u solves J^T r = 0 with r_i = (y_i - f_i(u)) / s_i, and an error e_i in surface i's
prediction shifts u by A^-1 J^T e / s exactly as a measurement error would. Each target's surface is its own
regression, so the surfaces' errors enter C's diagonal as (se_i / s_i)^2, se_i the standard error of the
surface's mean prediction at the optimum (x^T cov(beta) x, doe's se_mean); a surface fitted with no residual
dof has no error estimate and adds nothing (the surrogate check then says it is untested). The responses of one
battery come from one packing, so their surfaces' errors are not strictly independent; the diagonal is the
approximation made.
Parameters whose correlation reaches TRADE_CORRELATION are reported as trading: the data fix a
combination of them, not each, and the report says so next to the intervals rather than letting a falsely
precise optimum stand. An interval is cut at the factor's box, where the design says nothing beyond.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import stats as sps

from calibration.calibrate import natural_per_coded
from calibration.localise import ALPHA

LEVEL = 0.95
# |correlation| at which two parameters are reported as trading (the data fix their combination)
TRADE_CORRELATION = 0.9


def shared_discrepancy(res, discrepancy) -> np.ndarray:
    """C: the whitened discrepancy's covariance between different rows of one (test, quantity), zero elsewhere
    (priors' rows included, as zeros). Row i's discrepancy sd comes from its entry at the measured value."""
    from .discrepancy import discrepancy_term

    n = len(res.J)
    C = np.zeros((n, n))
    if not discrepancy:
        return C
    scaled, groups = np.zeros(n), [None] * n
    for i, (key, measured, noise) in enumerate(zip(res.keys, res.measured, res.noise)):
        term = discrepancy_term(key, float(measured), discrepancy)
        if term is not None and term.variance > 0 and noise.sd > 0:
            scaled[i], groups[i] = math.sqrt(term.variance) / noise.sd, (key.test, key.quantity)
    for i in range(n):
        for j in range(n):
            if i != j and groups[i] is not None and groups[i] == groups[j]:
                C[i, j] = scaled[i] * scaled[j]
    return C


def undetected_shift_sd(dof: int, rows: int) -> float:
    """k, in whitened units (a row's total sd): the shift shared by a quantity's ``rows`` rows that the lack of fit
    (chi2 on ``dof``, level ALPHA) detects with probability 1/2, sqrt(lambda_50 / rows)."""
    from scipy.optimize import brentq

    dof = max(int(dof), 1)
    critical = sps.chi2.ppf(1.0 - ALPHA, dof)
    lambda_50 = brentq(lambda lam: sps.ncx2.sf(critical, dof, lam) - 0.5, 1e-9, 1e4)
    return math.sqrt(lambda_50 / max(int(rows), 1))


def undetected_discrepancy(res, dof: int) -> np.ndarray:
    """C_u: for each (test, quantity), the whitened covariance of a shift shared by its rows of
    ``undetected_shift_sd`` in whitened units (the lack of fit's own units, whatever noise and stated discrepancy
    the weights hold), diagonal included; the priors' rows zero."""
    n = len(res.J)
    groups = [(key.test, key.quantity) for key in res.keys] + [None] * (n - len(res.keys))
    scaled = np.array([0.0 if g is None else undetected_shift_sd(dof, groups.count(g)) for g in groups])
    same = np.array([[g is not None and g == h for h in groups] for g in groups], bool).reshape(n, n)
    return np.where(same, np.outer(scaled, scaled), 0.0)


def surface_error(res) -> np.ndarray:
    """S: the whitened covariance of the surfaces' prediction errors at the optimum, diagonal (se_i / s_i)^2 on
    the target rows, zero on the priors' rows and where ``res`` carries no surface error."""
    n = len(res.J)
    S = np.zeros((n, n))
    se = getattr(res, "surface_se", None)
    if se is None or len(se) == 0:
        return S
    k = len(res.keys)
    S[:k, :k] = np.diag((np.asarray(se, float) / res.sd) ** 2)
    return S


def parameter_intervals(res, design, theta: dict[str, float], lack_of_fit, level: float = LEVEL,
                        discrepancy=(), undetected: bool = True) -> dict[str, Any]:
    """{"level", "scale", "quantile", "parameters": {name: {value, sd, low, high, at_bound}},
    "correlation": {a: {b: r}}, "trades": [...], "unidentified": [...]} at the optimum ``theta``.
    ``discrepancy``: the loop's model-form discrepancy entries (their shared part widens the intervals);
    ``undetected``: add the shift shared by each quantity's rows that the lack of fit would miss half the time."""
    free = list(res.free)
    J = np.asarray(res.J, float)
    JtJ = J.T @ J
    eigval, eigvec = np.linalg.eigh(JtJ)
    tiny = max(float(eigval.max(initial=0.0)), 1.0) * 1e-10
    inv = sum(np.outer(eigvec[:, k], eigvec[:, k]) / eigval[k] for k in range(len(free)) if eigval[k] > tiny) \
        if len(free) else np.zeros((0, 0))
    unidentified = [free[int(np.argmax(np.abs(eigvec[:, k])))] for k in range(len(free)) if eigval[k] <= tiny]
    fails = lack_of_fit.dof > 0 and lack_of_fit.p_value < ALPHA and lack_of_fit.per_dof > 1.0
    scale = float(lack_of_fit.per_dof) if fails else 1.0
    quantile = float(sps.t.ppf(0.5 + level / 2, lack_of_fit.dof) if fails else sps.norm.ppf(0.5 + level / 2))
    inv = np.asarray(inv, float)
    S = surface_error(res)
    C = shared_discrepancy(res, discrepancy) + S
    if undetected:
        C = C + undetected_discrepancy(res, lack_of_fit.dof)
    cov = scale * (inv + inv @ J.T @ C @ J @ inv)
    per_coded = np.array([natural_per_coded(design.factor(n), theta[n]) for n in free])
    cov_natural = cov * np.outer(per_coded, per_coded)
    sd = np.sqrt(np.clip(np.diag(cov_natural), 0.0, None))
    params = {}
    for j, name in enumerate(free):
        f = design.factor(name)
        value = float(theta[name])
        if name in unidentified or not math.isfinite(sd[j]):
            params[name] = {"value": value, "sd": None, "low": None, "high": None, "at_bound": None}
            continue
        low, high = value - quantile * sd[j], value + quantile * sd[j]
        cut = [side for side, hit in (("low", low < f.low), ("high", high > f.high)) if hit]
        params[name] = {"value": value, "sd": float(sd[j]), "low": float(max(low, f.low)),
                        "high": float(min(high, f.high)), "at_bound": cut or None}
    corr = {}
    trades = []
    for a in range(len(free)):
        corr[free[a]] = {}
        for b in range(len(free)):
            denom = math.sqrt(cov[a, a] * cov[b, b]) if cov[a, a] > 0 and cov[b, b] > 0 else 0.0
            r = float(cov[a, b] / denom) if denom > 0 else None
            corr[free[a]][free[b]] = r
            if b > a and r is not None and abs(r) >= TRADE_CORRELATION:
                trades.append({"parameters": [free[a], free[b]], "correlation": r,
                               "message": f"{free[a]} and {free[b]} trade (correlation {r:+.2f}): the measurements "
                                          "fix a combination of the two, not each; their intervals are wide along "
                                          "that line, and a prior or a test that moves only one of them separates "
                                          "them"})
    return {"level": level, "scale": scale, "quantile": quantile,
            "scaled_by_misfit": bool(fails), "parameters": params, "correlation": corr, "trades": trades,
            "unidentified": sorted(set(unidentified)),
            "undetected_shift": bool(undetected),
            "surface_error": bool(np.any(S)),
            "about": "from the whitened Jacobian of every target (measurement, discrepancy and simulator noise) "
                     "and the priors, the response surfaces' prediction error at the optimum, a discrepancy shared "
                     "by the rows of one quantity"
                     + (", and per quantity the further shift the lack of fit detects only half the time"
                        if undetected else "")
                     + "; widened by chi2/dof when the lack of fit fails; cut at the factor's box"}


def widen_to_measured(intervals: dict[str, Any], design, theta: dict[str, float], chi2_best: float,
                      points: list[tuple[dict, float]]) -> dict[str, Any]:
    """The intervals widened to every point measured on the batteries that the likelihood ratio does not reject.

    The intervals above are Wald intervals on the surfaces' slopes at the optimum: they take the objective as
    the quadratic those slopes define. Where a polish measured other points on the batteries themselves (the
    surfaces' optimum, the Jacobian's points, the anchors, the steps tried; ``polish.measured_points``), each is a
    measured section of the objective the slopes may not see: on DEM's hertz_strong the batteries fitted the
    targets as well at friction_pp 0.655 as at 0.908, a valley along friction_pp-friction_pw that the surfaces'
    curvature closed. A profile-likelihood interval at this level holds every value where the profile's chi2
    stays within D = scale x quantile^2 of the best (3.84 for 95 % with a passing lack of fit: the Wald interval
    +- quantile x sd of a quadratic objective); the profile lies at or below the chi2 of any point, so a point
    within D of the best has each of its parameter values inside the profile interval, and the interval is
    widened to hold it. A point beyond D is not: along the line from the best to it, a quadratic with its
    minimum at the best (the Wald interval's own assumption, here on measured chi2) reaches D at the fraction
    t = sqrt(D / (chi2_p - chi2_best)) of the way, and the interval is widened to that point of the line.
    Nothing is extrapolated beyond a measured point, and the intervals stay cut at the factor's box.
    ``points``: (natural parameters, the batteries' chi2 with the priors, as ``chi2_best``)."""
    if not intervals or not points:
        return intervals
    out = dict(intervals)
    out["parameters"] = {name: dict(row) for name, row in intervals["parameters"].items()}
    threshold = float(intervals["scale"]) * float(intervals["quantile"]) ** 2
    widened = set()
    for natural, chi2 in points:
        excess = float(chi2) - float(chi2_best)
        t = 1.0 if excess <= threshold else math.sqrt(threshold / excess)
        for name, row in out["parameters"].items():
            if row.get("low") is None or name not in natural:
                continue
            f = design.factor(name)
            reach = float(theta[name]) + t * (float(natural[name]) - float(theta[name]))
            for side, beyond, clip in (("low", reach < row["low"], max(reach, f.low)),
                                       ("high", reach > row["high"], min(reach, f.high))):
                if beyond and clip != row[side]:
                    row.setdefault("wald", {"low": row["low"], "high": row["high"]})
                    row[side] = float(clip)
                    widened.add(name)
                    if clip != reach:  # the widening reached the box: the interval is cut there now
                        cut = set(row.get("at_bound") or []) | {side}
                        row["at_bound"] = [s for s in ("low", "high") if s in cut]
    out["measured_points"] = {"count": len(points), "chi2_best": float(chi2_best), "threshold": threshold,
                              "widened": sorted(widened)}
    how = ("; widened to every point measured on the batteries within the likelihood ratio's threshold of the best, "
           "and along the line to each point beyond it as far as a quadratic through the two would allow")
    out["about"] = intervals["about"] if how in intervals["about"] else intervals["about"] + how
    return out


def covers(intervals: dict[str, Any], truth: dict[str, float]) -> dict[str, bool]:
    """For each parameter with an interval and a known true value: does the interval hold it?"""
    out = {}
    for name, row in (intervals or {}).get("parameters", {}).items():
        if name in truth and row.get("low") is not None:
            out[name] = bool(row["low"] <= truth[name] <= row["high"])
    return out
