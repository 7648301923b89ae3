"""A response some runs lack (doe.missing): the model the remaining runs can estimate, against a known truth."""
import numpy as np
import pytest

from doe import DoeError, fit_response, fractional_factorial
from doe.missing import estimable_terms, fit_available
from doe.terms import term_label

FACTORS = [("a", 0.0, 2.0), ("b", 0.0, 2.0), ("c", 0.0, 2.0), ("d", 0.0, 2.0), ("e", 0.0, 2.0)]
# the truth, in coded units: five main effects and one interaction (B x E), noise sd 0.05
TRUE = {"1": 10.0, "A": 2.0, "B": -3.0, "C": 1.5, "D": 0.5, "E": 4.0, "BE": 2.5}
NOISE_SD = 0.05


def _design_and_truth():
    d = fractional_factorial(FACTORS, ["E=ABCD"], center_runs=3, seed=3)
    x = d.coded
    y = (TRUE["1"] + TRUE["A"] * x[:, 0] + TRUE["B"] * x[:, 1] + TRUE["C"] * x[:, 2] + TRUE["D"] * x[:, 3]
         + TRUE["E"] * x[:, 4] + TRUE["BE"] * x[:, 1] * x[:, 4])
    y = y + np.random.default_rng(7).normal(0.0, NOISE_SD, d.n_runs)
    return d, y


def _lose_stiff_corners(d, y, n_lost=4):
    """The values at the first ``n_lost`` corners with E high and A high (a hold that did not settle there)."""
    y = y.copy()
    lost = [i for i in range(d.n_runs) if d.coded[i, 4] > 0.5 and d.coded[i, 0] > 0.5][:n_lost]
    y[lost] = np.nan
    return y, lost


def test_the_full_model_cannot_be_fitted_from_the_runs_left():
    d, y = _design_and_truth()
    y, lost = _lose_stiff_corners(d, y)
    assert len(lost) == 4
    with pytest.raises(DoeError):
        fit_response(d, y)


def test_the_runs_left_recover_the_truth_and_the_fit_says_what_it_left_out():
    d, y = _design_and_truth()
    y, _ = _lose_stiff_corners(d, y)
    fit = fit_available(d, y, response="y")
    labels = set(fit.term_labels)
    assert {"A", "B", "C", "D", "E", "BE"} <= labels  # every main effect and the true interaction
    est = dict(zip(["1"] + fit.term_labels, fit.params))
    # standard errors from the true noise (the design's (X'X)^-1 on the runs left times sd^2)
    se = dict(zip(["1"] + fit.term_labels, NOISE_SD * np.sqrt(np.diag(fit.ols.normalized_cov_params))))
    for name, value in TRUE.items():
        assert abs(est[name] - value) < 4 * se[name] + 1e-9, name
    for name in labels - set(TRUE):  # a term let in by chance is small: within noise
        assert abs(est[name]) < 4 * se[name]
    assert fit.n == d.n_runs - 4
    assert fit.reduction_log and "4 of 19 runs have no value" in fit.reduction_log[0]
    # the residual keeps an error estimate
    assert fit.has_error and fit.df_resid >= 2


def test_interactions_enter_only_where_the_data_support_them():
    d, y = _design_and_truth()
    y, _ = _lose_stiff_corners(d, y)
    kept, dropped = estimable_terms(d, y)
    kept_labels = {term_label(t, d.letters) for t in kept}
    # with noise sd 0.05 against effects of 0.5 or more, a null interaction passes p <= 0.10 by chance
    # about one time in ten; the true one always enters, and nothing is kept and dropped at once
    assert "BE" in kept_labels
    assert not set(kept) & set(dropped)
    assert len(kept_labels - {"A", "B", "C", "D", "E", "BE"}) <= 2


def test_a_response_every_run_holds_is_fitted_as_before():
    d, y = _design_and_truth()
    a, b = fit_available(d, y), fit_response(d, y)
    assert a.term_labels == b.term_labels
    np.testing.assert_allclose(a.params, b.params)
    assert a.reduction_log == []


def test_too_few_runs_is_a_clear_error():
    d, y = _design_and_truth()
    y = np.full_like(y, np.nan)
    y[:3] = [1.0, 2.0, 3.0]
    with pytest.raises(DoeError, match="cannot estimate any factor"):
        fit_available(d, y, response="e_ur")
