"""The log scale for a power law of a log-scaled factor (doe.transform), against closed forms.

A Hertzian packing's modulus grows as a power of the contact modulus E, and E is varied on a log scale,
so in coded units the modulus is an exponential: M = M0 * exp(b * x_E) exactly, here with 2 % multiplicative
scatter. Box-Cox must take the log there, keep the plain scale for a straight line with additive scatter,
and leave a moderate or a non-positive response alone. On the log scale the surface must return the closed
form between the corners, where the straight line's surface misses it, and the optimiser must invert it.
"""
import math

import numpy as np
import pytest
from scipy import stats

from doe import calibrate, fractional_factorial
from doe.fit import default_terms
from doe.missing import fit_available
from doe.transform import MIN_RATIO, choose

FACTORS = [("friction_pp", 0.2, 1.0), ("friction_pw", 0.2, 0.8), ("density", 2300.0, 2900.0),
           ("young_modulus_pa", 2.5e8, 4.0e9, True)]
M0_PA, B = 8.0e6, 1.4   # the modulus at the centre, and ln of its growth from the centre to a corner in E
FRICTION_GAIN = 0.2     # and a milder 20 % per coded unit of friction_pp, also multiplicative
SCATTER = 0.02


def _design():
    return fractional_factorial([f[:3] if len(f) == 3 else {"name": f[0], "low": f[1], "high": f[2], "log": True}
                                 for f in FACTORS], ["D=ABC"], center_runs=3, seed=2)


def _modulus(coded):
    return M0_PA * np.exp(B * coded[..., 3] + FRICTION_GAIN * coded[..., 0])


def _noisy_modulus(d, seed=4):
    return _modulus(d.coded) * np.exp(np.random.default_rng(seed).normal(0.0, SCATTER, d.n_runs))


def test_box_cox_takes_the_log_of_a_power_law_and_not_of_a_line():
    d = _design()
    y = _noisy_modulus(d)
    assert y.max() / y.min() > 10
    assert choose(d.coded, y, default_terms(d)).transform == "log"
    line = 1.0e7 + 6.0e6 * d.coded[:, 3] + 1.0e6 * d.coded[:, 0] \
        + np.random.default_rng(5).normal(0.0, 1e5, d.n_runs)
    assert line.max() / line.min() > MIN_RATIO
    assert choose(d.coded, line, default_terms(d)).transform == "none"


def test_a_moderate_or_non_positive_response_keeps_its_scale():
    d = _design()
    mild = 1.0e7 * np.exp(0.2 * d.coded[:, 3])  # max/min e^0.4 = 1.5
    assert choose(d.coded, mild, default_terms(d)).transform == "none"
    dilatancy = 3.0 + 6.0 * d.coded[:, 0]       # an angle that changes sign
    assert choose(d.coded, dilatancy, default_terms(d)).transform == "none"


def test_the_log_surface_returns_the_closed_form_between_the_corners():
    d = _design()
    y = _noisy_modulus(d)
    fit = fit_available(d, y, response="modulus")
    assert fit.transform == "log" and any("Box-Cox" in m for m in fit.messages)
    point = {"friction_pp": 0.6, "friction_pw": 0.5, "density": 2600.0, "young_modulus_pa": 1.0e9}
    coded = np.array([0.0, 0.0, 0.0, math.log10(1.0e9 / math.sqrt(2.5e8 * 4.0e9)) / math.log10(4.0e9 / math.sqrt(2.5e8 * 4.0e9))])
    truth = float(_modulus(coded))
    pred = fit.predict([point])[0]
    assert pred["pi_low"] < truth < pred["pi_high"]
    assert pred["mean"] == pytest.approx(truth, rel=3 * SCATTER)
    # the delta method's standard error: exp(m) times the log scale's, which the interval's half-width gives
    t_crit = stats.t.ppf(0.975, fit.error_variance_df)
    se_log = (math.log(pred["ci_high"]) - math.log(pred["mean"])) / t_crit
    assert pred["se_mean"] == pytest.approx(pred["mean"] * se_log, rel=1e-9)
    plain = fit_available(d, y, response="modulus", transform="none").predict([point])[0]
    # the straight-line surface bends the wrong way: at the centre it sits above the exponential's value by
    # about (cosh(B) - 1), the mean of the corners over the centre
    assert plain["mean"] > truth * (1 + 0.5 * (math.cosh(B) - 1))


def test_the_optimiser_inverts_the_log_surface():
    d = _design()
    y = _noisy_modulus(d)
    fit = fit_available(d, y, response="modulus")
    x_e = 0.3
    target = float(_modulus(np.array([0.0, 0.0, 0.0, x_e])))
    res = calibrate({"modulus": fit}, [{"response": "modulus", "value": target, "uncertainty": 0.01 * target}],
                    fixed={"friction_pp": 0.6, "friction_pw": 0.5, "density": 2600.0}, seed=1)
    centre = math.sqrt(2.5e8 * 4.0e9)
    expected = centre * (4.0e9 / centre) ** x_e
    assert res.parameters["young_modulus_pa"] == pytest.approx(expected, rel=0.05)
