"""Parameter intervals (calibration.intervals) on linear cases whose covariance is known by hand."""
import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import stats as sps

from calibration.intervals import TRADE_CORRELATION, covers, parameter_intervals, widen_to_measured
from calibration.stats import LackOfFit


def _design(**factors):
    made = {name: SimpleNamespace(name=name, low=lo, high=hi, log=False, half_range_t=(hi - lo) / 2)
            for name, (lo, hi) in factors.items()}
    return SimpleNamespace(factor=lambda n: made[n])


def _lof(per_dof: float, dof: int, p: float):
    return LackOfFit(per_dof * dof, dof, p, per_dof, (0.0, 2.0))


def test_one_parameter_by_hand():
    # whitened residual r = y - 2 u: J = -2 (one row), so var(u) = 1/4 in coded units; the factor spans
    # 0.2-1.0 (0.4 per coded unit): sd = 0.5 x 0.4 = 0.2, 95 % interval 0.6 +- 1.96 x 0.2 = 0.208-0.992
    res = SimpleNamespace(free=["friction_pp"], J=np.array([[-2.0]]))
    out = parameter_intervals(res, _design(friction_pp=(0.2, 1.0)), {"friction_pp": 0.6}, _lof(1.0, 5, 0.4),
                              undetected=False)
    row = out["parameters"]["friction_pp"]
    z = sps.norm.ppf(0.975)
    assert row["sd"] == pytest.approx(0.2)
    assert row["low"] == pytest.approx(0.6 - z * 0.2) and row["high"] == pytest.approx(0.6 + z * 0.2)
    assert row["at_bound"] is None and out["scale"] == 1.0
    # J = -1: sd 0.4, 0.6 +- 0.784 leaves the box on both sides and is cut there
    res = SimpleNamespace(free=["friction_pp"], J=np.array([[-1.0]]))
    row = parameter_intervals(res, _design(friction_pp=(0.2, 1.0)), {"friction_pp": 0.6},
                              _lof(1.0, 5, 0.4), undetected=False)["parameters"]["friction_pp"]
    assert (row["low"], row["high"], row["at_bound"]) == (0.2, 1.0, ["low", "high"])


def test_a_failing_fit_widens_by_birge_ratio_with_t_quantile():
    # chi2/dof 4 on 5 dof, p < 0.05: sd x 2 and the t(5) quantile (2.571) replaces 1.96
    res = SimpleNamespace(free=["friction_pp"], J=np.array([[-20.0]]))
    out = parameter_intervals(res, _design(friction_pp=(0.2, 1.0)), {"friction_pp": 0.6}, _lof(4.0, 5, 0.001),
                              undetected=False)
    row = out["parameters"]["friction_pp"]
    assert out["scaled_by_misfit"] and out["scale"] == 4.0
    assert row["sd"] == pytest.approx(2 * 0.4 / 20)
    assert out["quantile"] == pytest.approx(sps.t.ppf(0.975, 5))
    assert row["high"] - 0.6 == pytest.approx(out["quantile"] * row["sd"])


def test_parameters_that_trade_are_named():
    # two columns nearly parallel: rows (1, 1) and (1, 1.1) -> correlation of (J^T J)^-1 is -0.995
    J = np.array([[1.0, 1.0], [1.0, 1.1], [0.0, 0.0]]) * 10
    res = SimpleNamespace(free=["a", "b"], J=J)
    out = parameter_intervals(res, _design(a=(0.0, 1.0), b=(0.0, 1.0)), {"a": 0.5, "b": 0.5}, _lof(1.0, 1, 0.5),
                              undetected=False)
    inv = np.linalg.inv(J.T @ J)
    r = inv[0, 1] / math.sqrt(inv[0, 0] * inv[1, 1])
    assert out["correlation"]["a"]["b"] == pytest.approx(r) and abs(r) >= TRADE_CORRELATION
    assert out["trades"] and out["trades"][0]["parameters"] == ["a", "b"]


def test_an_unidentified_direction_gets_no_interval():
    res = SimpleNamespace(free=["a", "b"], J=np.array([[1.0, 0.0], [2.0, 0.0]]))
    out = parameter_intervals(res, _design(a=(0.0, 1.0), b=(0.0, 1.0)), {"a": 0.5, "b": 0.5}, _lof(1.0, 1, 0.5),
                              undetected=False)
    assert out["unidentified"] == ["b"] and out["parameters"]["b"]["sd"] is None
    assert covers(out, {"a": 0.5, "b": 0.5}) == {"a": True}


def test_a_discrepancy_shared_by_one_quantity_s_rows_does_not_average_out():
    """Two E' windows y_i = g u + delta + e_i, each row's total variance sigma^2 = 1.0^2 of which the shared
    discrepancy delta has d^2 = 0.6^2 (relative 0.1 of a measured 6): by hand var(u_hat) = var((y1 + y2) / 2g) =
    (4 d^2 + 2 (sigma^2 - d^2)) / 4 g^2 = (sigma^2 + d^2) / 2 g^2, not sigma^2 / 2 g^2 as for independent rows.
    A discrepancy on another quantity is not shared."""
    from calibration.discrepancy import Discrepancy
    from calibration.keys import ResponseKey
    from calibration.records import Noise, VarianceTerm

    g, sigma, d = 4.0, 1.0, 0.6
    keys = [ResponseKey.of("cct", "confined_modulus_pa", {"normal_stress_pa": s}) for s in (15e3, 30e3)]
    noise = [Noise(VarianceTerm(sigma**2, math.inf, "m"), VarianceTerm(0.0, math.inf, "s"))] * 2
    res = SimpleNamespace(free=["u"], J=np.array([[-g / sigma], [-g / sigma]]), keys=keys, measured=np.array([6.0, 6.0]),
                          noise=noise)
    shared = [Discrepancy(test="cct", relative_sd=0.1)]
    # coded = natural here (a factor of half-range 1 about 0)
    out = parameter_intervals(res, _design(u=(-1.0, 1.0)), {"u": 0.0}, _lof(1.0, 5, 0.4), discrepancy=shared,
                              undetected=False)
    assert out["parameters"]["u"]["sd"] ** 2 == pytest.approx((sigma**2 + d**2) / (2 * g**2))
    plain = parameter_intervals(res, _design(u=(-1.0, 1.0)), {"u": 0.0}, _lof(1.0, 5, 0.4), undetected=False)
    assert plain["parameters"]["u"]["sd"] ** 2 == pytest.approx(sigma**2 / (2 * g**2))
    other = parameter_intervals(res, _design(u=(-1.0, 1.0)), {"u": 0.0}, _lof(1.0, 5, 0.4),
                                discrepancy=[Discrepancy(test="dst", relative_sd=0.1)], undetected=False)
    assert other["parameters"]["u"]["sd"] == pytest.approx(plain["parameters"]["u"]["sd"])


def test_a_passing_fit_leaves_the_shift_it_cannot_see():
    """Two E' windows y_i = g u + e_i with sd sigma, a lack of fit on 5 dof. The shift shared by the two rows that
    the test detects half the time is k sigma with k^2 = lambda_50 / 2, lambda_50 the non-centrality at which
    chi2'(5, lambda) passes chi2_0.95(5) with probability 1/2. It moves u_hat = (y1 + y2) / 2g by k sigma / g, so
    by hand var(u_hat) = sigma^2 / 2 g^2 + k^2 sigma^2 / g^2. With a stated discrepancy d shared by the rows, the
    rows' sd is the total s = sqrt(sigma^2) the weights hold and the shift k s comes on top of d's
    (sigma^2 + d^2) / 2 g^2. A quantity measured on more rows gets less (k ~ 1 / sqrt(n))."""
    from scipy.optimize import brentq

    from calibration.discrepancy import Discrepancy
    from calibration.intervals import undetected_shift_sd
    from calibration.keys import ResponseKey
    from calibration.records import Noise, VarianceTerm

    critical = sps.chi2.ppf(0.95, 5)
    lambda_50 = brentq(lambda lam: sps.ncx2.sf(critical, 5, lam) - 0.5, 1e-6, 1e3)
    # at lambda_50 the critical value 11.07 is the median of chi2'(5, lambda): about 7, the mean 5 + 7 above it
    assert sps.ncx2.median(5, lambda_50) == pytest.approx(critical) and 6.5 < lambda_50 < 7.5
    k = math.sqrt(lambda_50 / 2)
    assert undetected_shift_sd(5, 2) == pytest.approx(k)
    assert undetected_shift_sd(5, 8) == pytest.approx(k / 2)

    g, sigma = 4.0, 1.0
    keys = [ResponseKey.of("cct", "confined_modulus_pa", {"normal_stress_pa": s}) for s in (15e3, 30e3)]
    noise = [Noise(VarianceTerm(sigma**2, math.inf, "m"), VarianceTerm(0.0, math.inf, "s"))] * 2
    res = SimpleNamespace(free=["u"], J=np.array([[-g / sigma], [-g / sigma]]), keys=keys, measured=np.array([6.0, 6.0]),
                          noise=noise)
    out = parameter_intervals(res, _design(u=(-1.0, 1.0)), {"u": 0.0}, _lof(1.0, 5, 0.4))
    assert out["undetected_shift"]
    assert out["parameters"]["u"]["sd"] ** 2 == pytest.approx(sigma**2 / (2 * g**2) + k**2 * sigma**2 / g**2)
    stated = parameter_intervals(res, _design(u=(-1.0, 1.0)), {"u": 0.0}, _lof(1.0, 5, 0.4),
                                 discrepancy=[Discrepancy(test="cct", relative_sd=0.1)])
    d = 0.6  # 10 % of the measured 6, shared, inside the rows' sd of 1 the weights hold
    assert stated["parameters"]["u"]["sd"] ** 2 == pytest.approx(
        (sigma**2 + d**2) / (2 * g**2) + k**2 * sigma**2 / g**2)


def test_the_surfaces_error_moves_the_optimum_as_the_measurement_noise_does():
    """One target y = g u measured with sd s; the optimum is found on a fitted surface whose mean prediction has
    standard error e. By hand u_hat = (y - e_f) / g, so var(u_hat) = (s^2 + e^2) / g^2: with s = 1, e = 0.75, g = 2
    in coded units, sd = 1.25 / 2 = 0.625 coded, 0.25 natural on a 0.2-1.0 box (0.4 per coded unit)."""
    from calibration.keys import ResponseKey

    key = ResponseKey("cct", "confined_modulus", "sigma_20")
    s, e, g = 1.0, 0.75, 2.0
    res = SimpleNamespace(free=["friction_pp"], J=np.array([[-g / s]]), keys=[key], sd=np.array([s]),
                          surface_se=np.array([e]))
    out = parameter_intervals(res, _design(friction_pp=(0.2, 1.0)), {"friction_pp": 0.6}, _lof(1.0, 5, 0.4),
                              undetected=False)
    assert out["parameters"]["friction_pp"]["sd"] == pytest.approx(math.sqrt(s**2 + e**2) / g * 0.4)
    assert out["surface_error"] is True
    # a surface with no error estimate (se 0) leaves the measurement-only sd 0.4 / 2 = 0.2
    res.surface_se = np.array([0.0])
    out = parameter_intervals(res, _design(friction_pp=(0.2, 1.0)), {"friction_pp": 0.6}, _lof(1.0, 5, 0.4),
                              undetected=False)
    assert out["parameters"]["friction_pp"]["sd"] == pytest.approx(0.2) and out["surface_error"] is False


def test_surface_standard_error_at_the_centre_of_an_orthogonal_design():
    """For an orthogonal two-level design with n runs, the intercept's variance is MSE / n and at the centre
    (coded 0) the mean prediction is the intercept alone: se = sqrt(MSE / n) (Montgomery, Design and Analysis
    of Experiments, the variance of a predicted mean in a 2^k design)."""
    from calibration.calibrate import surface_standard_error
    from doe import fit_response, full_factorial

    d = full_factorial([("a", 1.0, 3.0), ("b", 10.0, 30.0)], center_runs=0, replicates=3, seed=2)
    rng = np.random.default_rng(4)
    y = 5 + 2.0 * d.coded[:, 0] - 1.0 * d.coded[:, 1] + rng.normal(0, 0.3, d.n_runs)
    fit = fit_response(d, y, terms=["A", "B"], curvature=False)
    assert surface_standard_error(fit, {"a": 2.0, "b": 20.0}) == pytest.approx(math.sqrt(fit.mse / d.n_runs))


def _valley():
    """A quadratic objective chi2 = d^T H d (natural units) whose two parameters trade (correlation -0.95 of
    H's inverse), and Wald intervals taken from its diagonal alone: the view of slopes that miss the valley."""
    H = np.array([[4.0, 3.8], [3.8, 4.0]])
    theta = {"friction_pp": 0.0, "friction_pw": 0.0}
    design = _design(friction_pp=(-10.0, 10.0), friction_pw=(-10.0, 10.0))
    # coded = natural / 10: J_coded = 10 sqrt(H_ii) gives sd_natural = 1 / sqrt(H_ii)
    res = SimpleNamespace(free=list(theta), J=np.diag(10.0 * np.sqrt(np.diag(H))))
    wald = parameter_intervals(res, design, theta, _lof(1.0, 5, 0.4), undetected=False)
    return H, theta, design, wald


def test_a_measured_point_beyond_the_threshold_widens_to_the_profile_bound_of_a_quadratic():
    # the profile of friction_pp in a quadratic valley: chi2_profile(d) = d^2 / (H^-1)_11, so its 95 % bound is
    # d = z sqrt((H^-1)_11), with b at -H_12 / H_22 d. A point measured twice as far along that line has
    # chi2 = 4 z^2, and the quadratic through it and the best reaches z^2 half way: at the profile's bound.
    H, theta, design, wald = _valley()
    z = sps.norm.ppf(0.975)
    bound = z * math.sqrt(np.linalg.inv(H)[0, 0])
    assert wald["parameters"]["friction_pp"]["high"] < 0.5 * bound  # the diagonal's view is far too narrow
    d = np.array([2.0 * bound, -H[0, 1] / H[1, 1] * 2.0 * bound])
    point = {"friction_pp": d[0], "friction_pw": d[1]}
    out = widen_to_measured(wald, design, theta, 0.0, [(point, float(d @ H @ d))])
    row = out["parameters"]["friction_pp"]
    assert float(d @ H @ d) == pytest.approx(4 * z * z)
    assert row["high"] == pytest.approx(bound, rel=1e-12)
    assert row["low"] == wald["parameters"]["friction_pp"]["low"]  # nothing measured on that side
    assert row["wald"] == {"low": wald["parameters"]["friction_pp"]["low"],
                           "high": wald["parameters"]["friction_pp"]["high"]}
    assert out["measured_points"]["threshold"] == pytest.approx(z * z)
    assert out["measured_points"]["widened"] == ["friction_pp", "friction_pw"]


def test_a_measured_point_within_the_threshold_lies_inside_and_the_box_still_cuts():
    H, theta, design, wald = _valley()
    # chi2 1.0 above the best (below 3.84): the point itself, not beyond it
    inside = {"friction_pp": -1.5, "friction_pw": 1.4}
    out = widen_to_measured(wald, design, theta, 2.0, [(inside, 3.0)])
    assert out["parameters"]["friction_pp"]["low"] == pytest.approx(-1.5)
    assert out["parameters"]["friction_pw"]["high"] == pytest.approx(1.4)
    # a point outside the factor's box (the box is the design's, nothing is known beyond it) is cut there
    far = {"friction_pp": -30.0, "friction_pw": 0.0}
    out = widen_to_measured(wald, design, theta, 2.0, [(far, 2.5)])
    assert out["parameters"]["friction_pp"]["low"] == -10.0
    assert out["parameters"]["friction_pp"]["at_bound"] == ["low"]
    # a failing lack of fit scales the threshold as it scales the Wald intervals (Birge's ratio, t quantile)
    res = SimpleNamespace(free=list(theta), J=np.diag(10.0 * np.sqrt(np.diag(H))))
    failing = parameter_intervals(res, design, theta, _lof(2.0, 5, 0.01), undetected=False)
    threshold = 2.0 * sps.t.ppf(0.975, 5) ** 2  # 13.2
    wider = {"friction_pp": -2.5, "friction_pw": 2.4}
    assert failing["parameters"]["friction_pp"]["low"] > -2.5
    scaled = widen_to_measured(failing, design, theta, 0.0, [(wider, 10.0)])
    assert scaled["measured_points"]["threshold"] == pytest.approx(threshold)
    assert scaled["parameters"]["friction_pp"]["low"] == pytest.approx(-2.5)
    # the same excess with a passing fit (threshold 3.84) stops at sqrt(3.84 / 10) of the way
    passing = widen_to_measured(wald, design, theta, 0.0, [(wider, 10.0)])
    assert passing["parameters"]["friction_pp"]["low"] == pytest.approx(-2.5 * math.sqrt(sps.norm.ppf(0.975) ** 2 / 10))


def test_widening_twice_says_how_once():
    H, theta, design, wald = _valley()
    once = widen_to_measured(wald, design, theta, 0.0, [({"friction_pp": 0.1, "friction_pw": 0.0}, 0.5)])
    twice = widen_to_measured(once, design, theta, 0.0, [({"friction_pp": -0.1, "friction_pw": 0.0}, 0.5)])
    assert twice["about"] == once["about"] and once["about"].count("likelihood ratio") == 1
