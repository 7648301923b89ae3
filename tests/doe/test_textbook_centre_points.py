"""ANOVA with centre points against a published worked example.

Montgomery & Runger, Applied Statistics and Probability for Engineers, Example
S14-2 / Table S14-6 (the same data are Example 6.6 of Montgomery, Design and
Analysis of Experiments, 8th ed.): chemical process yield, a 2^2 in reaction time
A (30-40 min) and temperature B (150-160 F) with five centre points.

Factorial runs: (1) = 39.3, a = 40.9, b = 40.0, ab = 41.5; centre: 40.3, 40.5, 40.7, 40.2, 40.6.
Printed table: A SS 2.4025 F 55.87 p 0.0017; B 0.4225 F 9.83 p 0.0350; AB 0.0025 F 0.06
p 0.8237; Curvature 0.0027 F 0.06 p 0.8163; Error 0.1720 df 4 MS 0.0430.
Fitted first-order model (Example S14-3): yhat = 40.44 + 0.775 x1 + 0.325 x2.

By hand: contrasts A = 40.9 + 41.5 - 39.3 - 40.0 = 3.1, SS = 3.1^2/4 = 2.4025; B = 1.3, SS 0.4225;
AB = -0.1, SS 0.0025. yF = 40.425, yC = 40.46; SS_curv = 4*5*0.035^2/9 = 0.002722.
Centre deviations -0.16, 0.04, 0.24, -0.26, 0.14: SS_PE = 0.172, MS_PE = 0.043.
The printed p-values for the two tiny F ratios (0.8237, 0.8163) differ in the third
decimal from the F(1,4) tail at the printed SS (0.8213, 0.8137; F = 0.0581, 0.0633),
so those two are compared to 0.005; the others to their printed digits.
"""
import pytest

from doe import fit_response, full_factorial

FACTORIAL = {(-1, -1): 39.3, (1, -1): 40.9, (-1, 1): 40.0, (1, 1): 41.5}
CENTRE = [40.3, 40.5, 40.7, 40.2, 40.6]


@pytest.fixture(scope="module")
def design():
    return full_factorial([("time", 30, 40, "min"), ("temperature", 150, 160, "F")], center_runs=5,
                          randomize=False)


@pytest.fixture(scope="module")
def yields(design):
    fac = [FACTORIAL[(int(a), int(b))] for a, b in design.coded[design.factorial_mask]]
    return fac + CENTRE


def test_anova_with_curvature_and_pure_error(design, yields):
    fit = fit_response(design, yields, response="yield")
    printed = {"A": (2.4025, 55.87, 0.0017), "B": (0.4225, 9.83, 0.0350), "AB": (0.0025, 0.06, 0.8237),
               "Curvature": (0.0027, 0.06, 0.8163)}
    for source, (ss, f, p) in printed.items():
        row = fit.anova_row(source)
        assert row.df == 1
        assert row.sum_of_squares == pytest.approx(ss, abs=0.00005)
        assert row.f_value == pytest.approx(f, abs=0.005)
        p_tol = 0.005 if source in ("AB", "Curvature") else 0.00005
        assert row.p_value == pytest.approx(p, abs=p_tol)
    pe = fit.anova_row("Pure Error")
    assert pe.sum_of_squares == pytest.approx(0.1720, abs=5e-5) and pe.df == 4
    assert pe.mean_square == pytest.approx(0.0430, abs=5e-5)
    # the full model uses every factorial point: the residual is pure error alone
    assert fit.anova_row("Residual").df == 4 and fit.lack_of_fit_row is None


def test_first_order_model_lack_of_fit(design, yields):
    """Dropping AB moves its 0.0025 into lack of fit (1 df) tested against pure error."""
    fit = fit_response(design, yields, terms=["A", "B"], response="yield")
    assert fit.coefficients["Intercept"] == pytest.approx(40.44, abs=0.005)
    assert fit.coefficients["A"] == pytest.approx(0.775, abs=1e-9)
    assert fit.coefficients["B"] == pytest.approx(0.325, abs=1e-9)
    lof = fit.anova_row("Lack of Fit")
    assert lof.df == 1 and lof.sum_of_squares == pytest.approx(0.0025, abs=1e-9)
    assert lof.f_value == pytest.approx(0.0025 / 0.043, rel=1e-9)
    assert fit.anova_row("Curvature").sum_of_squares == pytest.approx(20 * 0.035**2 / 9, rel=1e-9)
    # natural units: x1 = (time - 35)/5, x2 = (temp - 155)/5
    nat = fit.natural_coefficients
    assert nat["time"] == pytest.approx(0.775 / 5) and nat["temperature"] == pytest.approx(0.325 / 5)
    assert nat["const"] == pytest.approx(364 / 9 - 0.155 * 35 - 0.065 * 155)
