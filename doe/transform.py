"""Whether a response is better modelled on a log scale: the Box-Cox comparison of lambda = 1 and lambda = 0.

Why: a granular packing's moduli follow power laws of the stress and of the contact stiffness (a Hertzian
contact's E' grows as E^(2/3) at a given stress), and a factor such as Young's modulus is varied on a log
scale over a decade or more. A power law of a log-scaled factor is an exponential in coded units, so a
first-order surface with interactions bends the wrong way between the corners: on hertz_strong's second
design (E 0.25-4 GPa) the linear surfaces of the unload-reload modulus over-predicted the mean of the eight
batteries at the kept optimum by 26-72 %; fitted to ln(y), by 17-24 % (`bench/reanalyse.py`). A moderate
response (max/min below 3) is not worth a transform (Montgomery, Design and Analysis of Experiments, 8th
ed., section 15.1.1; Design-Expert's rule of thumb).

The choice is Box and Cox's (1964): compare the residual sums of squares of the geometric-mean-scaled
responses, SS_E(1) on y and SS_E(0) = ydot^2 SS_E(ln y) with ydot the geometric mean, which are on one
scale. The log is taken only where the untransformed model lies outside the approximate confidence set for
lambda that Montgomery gives, SS_E(1) > SS_E(0) (1 + t^2_(alpha/2, nu) / nu): the plain scale is kept
unless the data reject it. A response that is not positive everywhere stays as it is.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .lstsq import rank, residual_ss
from .terms import model_matrix

TRANSFORMS = ("none", "log")
# below this max/min a transform changes little (Montgomery 15.1.1; Design-Expert's guide)
MIN_RATIO = 3.0


def forward(y, transform: str) -> np.ndarray:
    y = np.asarray(y, dtype=float)
    if transform == "none":
        return y
    if transform == "log":
        return np.log(y)
    raise ValueError(f"unknown transform {transform!r} (one of {', '.join(TRANSFORMS)})")


def inverse(z, transform: str):
    if transform == "none":
        return z
    if transform == "log":
        return np.exp(z)
    raise ValueError(f"unknown transform {transform!r} (one of {', '.join(TRANSFORMS)})")


@dataclass(frozen=True)
class Choice:
    transform: str
    reason: str
    sse_plain: float | None = None
    sse_log_scaled: float | None = None
    df: int = 0


def choose(coded: np.ndarray, y, terms, alpha: float = 0.05) -> Choice:
    """The scale to fit ``y`` (finite values, rows of ``coded``) on with the model ``terms``."""
    y = np.asarray(y, dtype=float)
    if y.size == 0 or not np.all(y > 0):
        return Choice("none", "not positive at every run")
    ratio = float(y.max() / y.min())
    if ratio < MIN_RATIO:
        return Choice("none", f"max/min {ratio:.3g} < {MIN_RATIO:g}")
    X = model_matrix(coded, terms)
    df = y.size - rank(X)
    if df <= 0:
        return Choice("none", "no residual degrees of freedom to judge a transform")
    sse_plain = residual_ss(X, y)
    ydot = math.exp(float(np.mean(np.log(y))))
    sse_log = ydot**2 * residual_ss(X, np.log(y))
    t = float(stats.t.ppf(1 - alpha / 2, df))
    bound = sse_log * (1 + t * t / df)
    if sse_plain > bound:
        return Choice("log", f"Box-Cox: SS_E {sse_plain:.4g} on y against {sse_log:.4g} on ln y (scaled by the "
                             f"geometric mean), beyond the {100 * (1 - alpha):g} % bound {bound:.4g}",
                      sse_plain, sse_log, df)
    return Choice("none", f"Box-Cox: SS_E {sse_plain:.4g} on y within the bound {bound:.4g} of ln y's "
                          f"{sse_log:.4g}", sse_plain, sse_log, df)
