"""Prediction intervals for the mean of m future runs, against the closed form of simple regression."""
import math

import numpy as np
import pytest
from scipy import stats

from doe import make_design
from doe.fit import fit_response


@pytest.mark.parametrize("m", [1, 2, 3])
def test_interval_for_the_mean_of_m_runs_is_the_simple_regression_one(m):
    """y = b0 + b1 x on x = -1, +1 and three centres: at x0 the interval for the mean of m new runs is
    yhat +- t s sqrt(1/m + 1/n + (x0 - xbar)^2 / Sxx) (the prediction interval for a new observation of
    simple linear regression, Montgomery & Runger, "Prediction of new observations", with 1 -> 1/m for
    the mean of m), with s^2 the residual mean square once the single-degree-of-freedom curvature sum of
    squares n_F n_C (ybar_F - ybar_C)^2 / (n_F + n_C) has its own row (Montgomery, Design and Analysis of
    Experiments, "Addition of center points to the 2^k design"), on n - 3 df."""
    design = make_design([{"name": "x", "low": -1.0, "high": 1.0}], full=True, center_runs=3, seed=3,
                         randomize=False)
    x = np.array([row["x"] for row in design.records("std")])
    y = 2.0 + 0.7 * x + np.array([0.11, -0.05, 0.08, -0.13, 0.02])[:len(x)]
    fit = fit_response(design, y)
    n = len(x)
    b1, b0 = np.polyfit(x, y, 1)
    corner, centre = y[x != 0], y[x == 0]
    ss_curvature = len(corner) * len(centre) * (corner.mean() - centre.mean()) ** 2 / n
    s2 = (float(np.sum((y - (b0 + b1 * x)) ** 2)) - ss_curvature) / (n - 3)
    sxx = float(np.sum((x - x.mean()) ** 2))
    x0 = 0.4
    half = stats.t.ppf(0.975, n - 3) * math.sqrt(s2 * (1 / m + 1 / n + (x0 - x.mean()) ** 2 / sxx))
    pred = fit.predict([{"x": x0}], 0.05, n_future=m)[0]
    assert math.isclose(pred["mean"], b0 + b1 * x0, rel_tol=1e-12)
    assert math.isclose(pred["pi_high"] - pred["mean"], half, rel_tol=1e-9)
    assert math.isclose(pred["mean"] - pred["pi_low"], half, rel_tol=1e-9)
