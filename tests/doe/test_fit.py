"""Fits: intervals, PRESS, natural-unit equation, hierarchical reduction, bad input."""
import numpy as np
import pytest
import statsmodels.api as sm

from doe import DoeError, fit_response, full_factorial, make_design


@pytest.fixture(scope="module")
def replicated():
    d = full_factorial([("a", 1.0, 3.0), ("b", 10.0, 30.0), ("c", 0.1, 0.5)], center_runs=3, replicates=2, seed=5)
    x = d.coded
    rng = np.random.default_rng(11)
    # known truth: strong A, AB interaction with B main effect tiny, no C
    y = 5 + 2.0 * x[:, 0] + 0.01 * x[:, 1] + 1.5 * x[:, 0] * x[:, 1] + rng.normal(0, 0.2, d.n_runs)
    return d, y


def test_intervals_match_an_independent_ols(replicated):
    d, y = replicated
    fit = fit_response(d, y, terms=["A", "B", "AB"], curvature=False)
    X = np.column_stack([np.ones(d.n_runs), d.coded[:, 0], d.coded[:, 1], d.coded[:, 0] * d.coded[:, 1]])
    ref = sm.OLS(y, X).fit()
    pt = {"a": 2.5, "b": 12.0, "c": 0.3}
    xa, xb = (2.5 - 2) / 1, (12 - 20) / 10
    frame = ref.get_prediction(np.array([[1, xa, xb, xa * xb]])).summary_frame(alpha=0.05)
    p = fit.predict([pt])[0]
    assert p["mean"] == pytest.approx(frame["mean"][0])
    assert p["ci_low"] == pytest.approx(frame["mean_ci_lower"][0])
    assert p["pi_high"] == pytest.approx(frame["obs_ci_upper"][0])
    # with a curvature row, the error variance is that of OLS with a centre-run indicator added
    curved = fit_response(d, y, terms=["A", "B", "AB"])
    ref_c = sm.OLS(y, np.column_stack([X, d.center_mask.astype(float)])).fit()
    assert curved.mse == pytest.approx(ref_c.mse_resid) and curved.error_variance_df == ref_c.df_resid


def test_press_equals_leave_one_out(replicated):
    d, y = replicated
    fit = fit_response(d, y, terms=["A", "B", "AB"])
    press = 0.0
    for i in range(d.n_runs):
        keep = np.arange(d.n_runs) != i
        Xi = fit.X[keep]
        beta = np.linalg.lstsq(Xi, y[keep], rcond=None)[0]
        press += (y[i] - fit.X[i] @ beta) ** 2
    assert fit.press == pytest.approx(press)
    assert fit.pred_r_squared == pytest.approx(1 - press / np.sum((y - y.mean()) ** 2))


def test_natural_equation_reproduces_coded_predictions(replicated):
    d, y = replicated
    fit = fit_response(d, y)
    nat = fit.natural_coefficients
    rng = np.random.default_rng(3)
    for _ in range(5):
        a, b, c = rng.uniform(1, 3), rng.uniform(10, 30), rng.uniform(0.1, 0.5)
        vals = {"const": 1, "a": a, "b": b, "c": c, "a*b": a * b, "a*c": a * c, "b*c": b * c}
        manual = sum(nat[k] * v for k, v in vals.items())
        assert manual == pytest.approx(fit.predict({"a": a, "b": b, "c": c})[0]["mean"])


def test_hierarchical_reduction_keeps_parents(replicated):
    d, y = replicated
    fit = fit_response(d, y)                       # A B C AB AC BC
    red = fit.reduce(alpha_out=0.05)
    assert "AB" in red.term_labels and "B" in red.term_labels   # B kept for AB although B is null
    assert "C" not in red.term_labels and "AC" not in red.term_labels
    assert red.reduction_log and all(s.startswith("removed") for s in red.reduction_log)
    assert red.df_resid > fit.df_resid


def test_replicated_fit_reports_lack_of_fit_and_statistics(replicated):
    d, y = replicated
    fit = fit_response(d, y, terms=["A"])
    sources = [r.source for r in fit.anova]
    assert sources[:2] == ["Model", "A"] and "Curvature" in sources and "Lack of Fit" in sources
    lof = fit.anova_row("Lack of Fit")
    assert lof.p_value < 0.001                     # the omitted AB interaction shows as lack of fit
    st = fit.to_dict()["fit_statistics"]
    assert 0 < st["adj_r_squared"] < st["r_squared"] < 1
    import json
    json.dumps(fit.to_dict())                      # JSON-ready


def test_missing_values_and_bad_terms():
    d = make_design([("a", 0, 1), ("b", 0, 1), ("c", 0, 1), ("d", 0, 1)], center_runs=3, seed=2)
    y = np.arange(d.n_runs, dtype=float)
    y[0] = np.nan
    fit = fit_response(d, y, terms=["A", "B"])
    assert fit.n == d.n_runs - 1 and "left out" in fit.messages[0]
    with pytest.raises(DoeError, match="aliased"):
        fit_response(d, np.arange(d.n_runs, dtype=float), terms=["A", "AB", "CD"])
    with pytest.raises(DoeError, match="unknown factor"):
        fit_response(d, np.arange(d.n_runs, dtype=float), terms=["A", "zz*a"])
    with pytest.raises(DoeError, match="values for"):
        fit_response(d, [1.0, 2.0])


def test_ccd_quadratic_fit_and_reduction_keep_parents():
    """Rotatable CCD; truth has A^2 and AB but no B^2: reduction drops B^2 only, keeping B for AB."""
    from doe import augment_ccd
    d = augment_ccd(full_factorial([("a", 0.0, 1.0), ("b", 10.0, 20.0)], center_runs=3, seed=1), "rotatable", 3)
    x = d.coded
    y = (3 + 1.0 * x[:, 0] + 0.8 * x[:, 0] ** 2 + 0.3 * x[:, 0] * x[:, 1]
         + np.random.default_rng(0).normal(0, 0.05, d.n_runs))
    fit = fit_response(d, y)
    assert fit.term_labels == ["A", "B", "AB", "A^2", "B^2"]
    assert "Curvature" not in [r.source for r in fit.anova]      # squares are in the model instead
    assert fit.coefficients["A^2"] == pytest.approx(0.8, abs=0.1)
    red = fit.reduce(alpha_out=0.05)
    assert red.term_labels == ["A", "B", "AB", "A^2"]
    with pytest.raises(DoeError, match="not a number"):
        from doe import fit_responses
        fit_responses(d, [{"y": "bad"}] * d.n_runs)
