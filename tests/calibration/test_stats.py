"""Each statistic of the diagnosis against a textbook or analytic case."""
import math

import numpy as np
import pytest
from scipy import stats as sps
from statsmodels.stats.multitest import multipletests

from calibration import stats
from calibration.records import Noise, VarianceTerm


def test_score_statistic_is_the_exact_ssr_drop_on_a_linear_problem():
    # Frisch-Waugh-Lovell: on a linear model the score statistic of an added regressor equals the drop of
    # the residual sum of squares when it is added and every parameter re-optimised.
    rng = np.random.default_rng(1)
    J = rng.standard_normal((15, 4))
    s = rng.standard_normal(15)
    r = J @ rng.standard_normal(4) + 0.7 * s + 0.3 * rng.standard_normal(15)
    M = stats.residual_maker(J)
    ssr_base = float(np.sum((M @ r) ** 2))
    both = np.column_stack([J, s])
    coef, *_ = np.linalg.lstsq(both, r, rcond=None)
    ssr_with = float(np.sum((r - both @ coef) ** 2))
    score = stats.score_test(r, s, M)
    assert score.gamma == pytest.approx(coef[-1], rel=1e-10)       # and its gamma is the refitted coefficient
    assert score.lm == pytest.approx(ssr_base - ssr_with, rel=1e-10)
    assert score.explained == pytest.approx((ssr_base - ssr_with) / ssr_base, rel=1e-10)
    assert score.p_value == pytest.approx(0.5 * sps.chi2.sf(score.lm, 1))


def test_score_test_is_one_sided():
    J = np.eye(6)[:, :2]
    s = np.array([0, 0, 1.0, 1.0, 1.0, 1.0])
    r = -2.0 * s        # the effect would have to act backwards
    score = stats.score_test(r, s, stats.residual_maker(J))
    assert score.gamma < 0 and score.lm == 0.0 and score.p_value == 1.0


def test_residual_maker_removes_what_the_parameters_absorb():
    J = np.array([[1.0, 0], [1, 1], [1, 2], [1, 3]])
    M = stats.residual_maker(J)
    assert np.allclose(M @ J, 0) and np.allclose(M, M.T) and np.allclose(M @ M, M)
    assert np.trace(M) == pytest.approx(2.0)


def test_holm_matches_the_textbook_step_down_and_statsmodels():
    p = [0.01, 0.04, 0.03, 0.005]
    # sorted 0.005 x 4 = 0.02, 0.01 x 3 = 0.03, 0.03 x 2 = 0.06, 0.04 x 1 -> max(0.06, 0.04) = 0.06
    assert np.allclose(stats.holm(p), [0.03, 0.06, 0.06, 0.02])
    rng = np.random.default_rng(2)
    q = rng.uniform(0, 0.2, 9)
    assert np.allclose(stats.holm(q), multipletests(q, method="holm")[1])


def test_trend_recovers_a_known_slope_with_the_textbook_standard_error():
    x = np.array([10.5e3, 24.0e3, 38.3e3, 52.4e3])
    y = 300.0 + 0.05 * x
    t = stats.weighted_trend(x, y, np.full(4, 100.0))
    assert t.slope == pytest.approx(0.05) and t.intercept == pytest.approx(300.0)
    # equal weights: se(slope) = sd / sqrt(sum (x - mean)^2)
    assert t.slope_se == pytest.approx(100.0 / math.sqrt(np.sum((x - x.mean()) ** 2)))
    # on noisy data the estimate lies within its standard errors as often as a normal says
    rng = np.random.default_rng(3)
    inside = 0
    for _ in range(400):
        tn = stats.weighted_trend(x, y + 100.0 * rng.standard_normal(4), np.full(4, 100.0))
        inside += abs(tn.slope - 0.05) <= 1.96 * tn.slope_se
    assert 0.92 <= inside / 400 <= 0.98
    with pytest.raises(ValueError):
        stats.weighted_trend([1.0, 1.0], [2.0, 3.0], [1.0, 1.0])


def test_lack_of_fit_is_chi2_with_known_variances_and_keeps_its_size_with_three_replicates():
    rng = np.random.default_rng(4)
    J = rng.standard_normal((16, 4))
    M = stats.residual_maker(J)
    r = M @ rng.standard_normal(16) * 1.3
    lof = stats.lack_of_fit(r, M, np.full(16, np.inf))
    assert lof.dof == 12 and lof.p_value == pytest.approx(sps.chi2.sf(r @ r, 12))
    assert lof.noise_band == pytest.approx((1 - 2 * math.sqrt(2 / 12), 1 + 2 * math.sqrt(2 / 12)))
    # variances estimated from 3 replicates (df 2): residuals are t_2-like; the test must still reject
    # about 5 % of true models, where a chi2 reference would reject far more
    df = np.full(16, 2.0)
    alarms_mc, alarms_chi2, n = 0, 0, 300
    draws = stats.null_residuals(M, df, n_sim=4000, seed=9)
    for _ in range(n):
        z = M @ rng.standard_normal(16)
        rr = z / np.sqrt(rng.chisquare(2, 16) / 2)
        alarms_mc += stats.lack_of_fit(rr, M, df, draws=draws).p_value < 0.05
        alarms_chi2 += sps.chi2.sf(rr @ rr, 12) < 0.05
    print(f"false alarms at alpha 0.05: calibrated null {alarms_mc / n:.3f}, chi2 reference {alarms_chi2 / n:.3f}")
    assert 0.02 <= alarms_mc / n <= 0.09
    assert alarms_chi2 / n > 0.2


def test_boundary_likelihood_ratio_is_half_chi2():
    # Self & Liang (1987): one parameter on its boundary -> 0.5 chi2_0 + 0.5 chi2_1; 2.71 is the 5 % point
    assert stats.boundary_lr_pvalue(2.7055) == pytest.approx(0.05, abs=1e-4)
    assert stats.boundary_lr_pvalue(0.0) == 1.0


def test_satterthwaite_degrees_of_freedom_of_the_noise():
    # two equal variances of 2 df each: (v1 + v2)^2 / (v1^2/2 + v2^2/2) = 4
    n = Noise(VarianceTerm(1.0, 2, "replicates"), VarianceTerm(1.0, 2, "centre"))
    assert n.df == pytest.approx(4.0) and n.variance == 2.0
    assert Noise(VarianceTerm(1.0, math.inf, "stated"), VarianceTerm(0.0, 2, "none")).df == math.inf


def test_bic_adds_log_n_per_parameter():
    assert stats.bic(10.0, 3, 20) == pytest.approx(10.0 + 3 * math.log(20))


def test_noise_band_never_goes_below_zero():
    """chi2/dof is a sum of squares over dof: with 6 dof 1 - 2 sqrt(2/6) < 0, and the band stops at 0."""
    M = np.eye(6)
    lof = stats.lack_of_fit(np.ones(6), M, np.full(6, np.inf))
    assert lof.noise_band == pytest.approx((0.0, 1 + 2 * math.sqrt(2 / 6)))


def test_directed_test_is_the_one_sided_score_test_for_one_candidate_with_known_variances():
    """One candidate, every variance known: max(0, u.r)^2 is one-sided chi2_1, p = P(chi2_1 > T) / 2."""
    rng = np.random.default_rng(11)
    M = stats.residual_maker(rng.standard_normal((12, 3)))
    s = rng.standard_normal(12)
    u = M @ s / np.linalg.norm(M @ s)
    r = M @ rng.standard_normal(12) + 2.5 * u
    test = stats.directed_test(r, M, [s])
    assert test.lm == pytest.approx(float(u @ r) ** 2)
    assert test.lm == pytest.approx(stats.score_test(r, s, M).lm)
    assert test.p_value == pytest.approx(0.5 * sps.chi2.sf(test.lm, 1))
    assert stats.directed_test(-r, M, [s]).p_value == 1.0  # the signature pointing away explains nothing


def test_directed_test_null_of_the_largest_of_k_orthogonal_candidates():
    """k orthogonal signatures, M = I, variances known: the k projections are independent N(0, 1), so
    P(max_e max(0, z_e)^2 >= t) = 1 - (1 - P(chi2_1 > t) / 2)^k; the simulated null (df huge) matches it."""
    k, n = 4, 10
    signatures = list(np.eye(n)[:k] * 3.0)
    r = np.zeros(n)
    r[2] = 2.2
    M = np.eye(n)
    draws = stats.null_residuals(M, np.full(n, 1e9), n_sim=40000, seed=5)
    exact = 1.0 - (1.0 - 0.5 * sps.chi2.sf(2.2**2, 1)) ** k
    assert stats.directed_test(r, M, signatures, draws).p_value == pytest.approx(exact, abs=0.005)
    # with known variances (no draws) Bonferroni bounds it from above
    assert exact <= stats.directed_test(r, M, signatures).p_value <= k * 0.5 * sps.chi2.sf(2.2**2, 1) + 1e-12


def test_directed_test_and_its_combination_keep_their_size_with_three_replicates():
    """True models, variances from 3 replicates (df 2), three candidates: the directed test and Holm
    over it and the omnibus test each reject about 5 %, not more."""
    rng = np.random.default_rng(21)
    n_res = 14
    M = stats.residual_maker(rng.standard_normal((n_res, 4)))
    df = np.full(n_res, 2.0)
    signatures = [rng.standard_normal(n_res) for _ in range(3)]
    draws = stats.null_residuals(M, df, n_sim=4000, seed=3)
    directed, combined, n = 0, 0, 400
    for _ in range(n):
        rr = (M @ rng.standard_normal(n_res)) / np.sqrt(rng.chisquare(2, n_res) / 2)
        p_dir = stats.directed_test(rr, M, signatures, draws).p_value
        p_omni = stats.lack_of_fit(rr, M, df, draws=draws).p_value
        directed += p_dir < 0.05
        combined += stats.combined_p(p_omni, p_dir) < 0.05
    print(f"false alarms at alpha 0.05: directed {directed / n:.3f}, Holm with the omnibus {combined / n:.3f}")
    assert 0.02 <= directed / n <= 0.09
    assert combined / n <= 0.08


def test_holm_of_two_is_twice_the_smaller_p():
    assert stats.combined_p(0.03, 0.2) == pytest.approx(0.06)
    assert stats.combined_p(0.3, 0.01) == pytest.approx(0.02)
    assert stats.combined_p(0.04, None) == 0.04
    assert stats.combined_p(0.9, 0.8) == 1.0


def test_weighted_rms_is_the_root_mean_square_of_the_standardised_residuals():
    # (3, 4, None): sqrt((9 + 16) / 2); a missing residual is left out, none at all is NaN
    assert math.isclose(stats.weighted_rms([3.0, 4.0, None]), math.sqrt(12.5))
    assert math.isnan(stats.weighted_rms([]))


def test_a_test_within_its_own_noise_never_fails_however_exactly_the_fit_absorbs_it():
    """One free parameter reaches the first residual only (M = diag(0, 1, 1)): under the fitted null
    that residual is exactly 0, so any residual left there (an optimum held at a bound) is "impossible".
    Against the noise alone its p is P(chi2_1 >= 0.04) = 0.841 (known variances), which is the answer;
    a residual 3 sd off on a test the fit cannot reach keeps the fitted null's p, P(chi2_1 >= 9) = 0.0027."""
    M = stats.residual_maker(np.array([[1.0], [0.0], [0.0]]))
    r = np.array([0.2, 3.0, -0.5])
    first, second = np.array([0]), np.array([1])
    assert stats.group_pvalue(r, first, M, None) < 1e-6           # the fitted null alone: "fails"
    assert stats.own_check_pvalue(r, first, M, None, None) == pytest.approx(sps.chi2.sf(0.04, 1), rel=1e-9)
    assert stats.own_check_pvalue(r, second, M, None, None) == pytest.approx(sps.chi2.sf(9.0, 1), rel=1e-9)
    # the same with variances from three replicates (Monte Carlo nulls): still far from failing
    df = np.full(3, 2.0)
    draws, unfitted = stats.null_residuals(M, df, seed=1), stats.null_residuals(np.eye(3), df, seed=1)
    assert stats.group_pvalue(r, first, M, draws) < 1e-3
    assert stats.own_check_pvalue(r, first, M, draws, unfitted) > 0.5


def test_a_signature_s_noise_attenuates_the_share_it_explains_by_one_minus_its_noise_share():
    """Errors in variables by hand: a residual r = t (the true signature, |t|^2 = 4) and a signature measured as
    s = t + e with e orthogonal to t, |e|^2 = 1. LM / |r|^2 = (s.r)^2 / (|s|^2 |r|^2) = 16 / (5 x 4) = 0.8, while
    the effect explains all of it; the noise share E|e|^2 / |s|^2 = 1/5, and 0.8 / (1 - 1/5) = 1."""
    from calibration.attribute import MAX_CORRECTED_NOISE, explained_share

    t = np.array([2.0, 0.0, 0.0])
    s = t + np.array([0.0, 1.0, 0.0])
    observed = stats.score_test(t, s, np.eye(3)).explained
    assert observed == pytest.approx(0.8)
    assert explained_share(observed, 1.0 / 5.0) == pytest.approx(1.0)
    # a signature mostly noise is read as it stands, and a known-clean one is not touched
    assert explained_share(0.2, MAX_CORRECTED_NOISE) == 0.2 and explained_share(0.2, 0.0) == 0.2


def test_a_signature_s_noise_shortens_the_strength_it_reads_by_the_same_factor():
    """The same case for the step: gamma = s.r / |s|^2 = 4 / 5 where the true step is 1 (r = t, the signature per
    unit strength), and 0.8 / attenuation(1/5) = 1. Then by simulation, where the reliability ratio holds (many
    rows): t = 0.5 on 40 rows (|t|^2 = 10), e ~ N(0, 0.25^2) per row (E|e|^2 = 2.5), the plain step averages
    10 / 12.5 = 0.8 and the step divided by attenuation(noise_share), the share read from each draw as the
    diagnosis reads it, averages 1 within 2 %. What is left is second order: dividing by a noisy |s|^2 adds about
    Var|s|^2 / (E|s|^2)^2 = (40 (4 x 0.25 x 0.0625 + 2 x 0.0625^2)) / 12.5^2 = 1.8 %, against the 20 % taken out."""
    from calibration.attribute import MAX_CORRECTED_NOISE, attenuation, noise_share

    t = np.array([2.0, 0.0, 0.0])
    s = t + np.array([0.0, 1.0, 0.0])
    gamma = stats.score_test(t, s, np.eye(3)).gamma
    assert gamma == pytest.approx(0.8)
    assert gamma / attenuation(1.0 / 5.0) == pytest.approx(1.0)
    assert attenuation(MAX_CORRECTED_NOISE) == 1.0 and attenuation(0.0) == 1.0
    rng = np.random.default_rng(5)
    t, M, noise_var = np.full(40, 0.5), np.eye(40), np.full(40, 0.25 ** 2)
    plain, corrected = [], []
    for _ in range(4000):
        s = t + rng.normal(0.0, 0.25, 40)
        g = stats.score_test(t, s, M).gamma
        plain.append(g)
        corrected.append(g / attenuation(noise_share(M, s, noise_var)))
    assert np.mean(plain) == pytest.approx(0.8, rel=0.02)
    assert np.mean(corrected) == pytest.approx(1.0, rel=0.02)
    assert abs(np.mean(corrected) - 1.0) < 0.1 * abs(np.mean(plain) - 1.0)  # nine tenths of the bias taken out
