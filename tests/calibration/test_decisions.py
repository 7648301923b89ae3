"""The added effect's range (``calibration.decisions.effect_range``) and its widening when the optimum
pins the strength at the top (``widened_top``), on the catalogue's own plausible ranges.

Every expected number follows from the rule and the catalogue entry: rolling resistance is "off" at
mu_r 0 and plausible up to 0.5; particle shape is "off" at aspect ratio 1 and plausible up to 2, which
is also the engine's limit for two touching spheres.
"""
import pytest

from calibration.attribute import PLAUSIBLE_SLACK
from calibration.decisions import effect_range, widened_top
from engine.candidates import candidates


def test_the_plausible_range_or_twice_the_estimate_when_larger():
    rolling = candidates()["rolling_epsd2"]
    low, high, log = effect_range(rolling, strength=0.124)
    assert (low, log) == (0.0, False) and high == pytest.approx(rolling.plausible_range[1])
    assert effect_range(rolling, strength=0.3)[1] == pytest.approx(2 * 0.3)
    assert effect_range(rolling)[1] == pytest.approx(rolling.plausible_range[1])
    shape = candidates()["particle_shape"]
    assert effect_range(shape, strength=1.3)[:2] == pytest.approx((1.0, 2.0))


def test_never_past_the_slack_or_the_engines_limit():
    rolling = candidates()["rolling_epsd2"]
    assert effect_range(rolling, strength=3.0)[1] == pytest.approx(PLAUSIBLE_SLACK * rolling.plausible_range[1])
    shape = candidates()["particle_shape"]
    assert effect_range(shape, strength=1.9)[1] == pytest.approx(2.0)  # two-sphere clumps stop at 2


def test_a_pinned_strength_gets_twice_the_range_once_the_cap_allows():
    rolling = candidates()["rolling_epsd2"]
    assert widened_top(rolling, 0.248) == pytest.approx(0.496)
    assert widened_top(rolling, 0.8) == pytest.approx(PLAUSIBLE_SLACK * rolling.plausible_range[1])
    assert widened_top(rolling, PLAUSIBLE_SLACK * rolling.plausible_range[1]) is None
    shape = candidates()["particle_shape"]
    assert widened_top(shape, 1.6) == pytest.approx(2.0) and widened_top(shape, 2.0) is None


def test_a_switch_effect_is_never_widened():
    hertz = candidates()["hertz_mindlin"]
    low, high, log = effect_range(hertz, reference=1.0e9)
    assert log and (low, high) == pytest.approx((2.5e8, 4.0e9))
    assert widened_top(hertz, high) is None


# ``judge``: the likelihood-ratio test decides between two fits of the same residuals; the lack of fit
# only vetoes a fit that passed and no longer does. The p-values below are inputs (each iteration's own
# Monte Carlo p-value), the expected LR p-value is the Self & Liang mixture, 1/2 P(chi2_1 > lr).

def _judge(**kw):
    from calibration.decisions import judge
    base = dict(chi2_before=68.7, chi2_after=18.6, n_residuals=4, free_before=3, free_after=3)
    return judge(candidates()["rolling_epsd2"], **{**base, **kw})


def test_a_significant_fall_between_two_failing_fits_is_kept_whatever_their_p_values():
    """Both fits far outside the noise: the second's Monte Carlo p-value (5 draws in 20,001) below the
    first's (12 in 20,001) says nothing about which is better; chi2 68.7 -> 18.6 on the same residuals does."""
    from scipy import stats
    d = _judge(lof_p_before=12 / 20001, lof_p_after=5 / 20001)
    assert d.accepted
    assert d.lr == pytest.approx(50.1) and d.p_value == pytest.approx(0.5 * stats.chi2.sf(50.1, 1))


def test_a_passing_lack_of_fit_turned_failing_is_rejected():
    assert not _judge(chi2_before=6.0, chi2_after=1.0, lof_p_before=0.2, lof_p_after=0.01).accepted
    assert _judge(chi2_before=6.0, chi2_after=1.0, lof_p_before=0.2, lof_p_after=0.3).accepted


def test_a_fall_within_chance_is_rejected():
    # lr 2: 1/2 P(chi2_1 > 2) = 0.079 > 0.05, and BIC falls by 2 only (same free parameters): not enough
    d = _judge(chi2_before=20.0, chi2_after=18.0, lof_p_before=0.001, lof_p_after=0.002)
    assert d.p_value == pytest.approx(0.0786, abs=1e-4) and not d.accepted
    assert not _judge(chi2_before=18.0, chi2_after=20.0, lof_p_before=0.001, lof_p_after=0.002).accepted


# ``widened_box``: a base factor pinned at a box edge short of where its values usually lie (engine.lab.bounds'
# Typical ranges: friction coefficients 0.1-1.0, thesis Table 4.4; contact stiffness 1e4-1e10 N/m) gets the
# box's width more on that side, once; at its typical limit it is the diagnosis's business.

def test_a_pinned_stiffness_gets_the_box_width_more_within_its_typical_range():
    from calibration.decisions import widened_box
    k = {"name": "particle_stiffness_n_per_m", "low": 1.0e6, "high": 3.0e6}
    assert widened_box(k, "high")["high"] == pytest.approx(5.0e6)
    assert widened_box(k, "low")["low"] == pytest.approx(1.0e4)          # 1e6 - 2e6 < 0: the typical floor
    assert widened_box({**k, "log": True}, "high")["high"] == pytest.approx(9.0e6)  # x (3e6 / 1e6)
    assert widened_box({**k, "high": 1.0e10}, "high") is None            # already at the typical ceiling


def test_friction_at_its_typical_ceiling_is_not_widened_and_below_it_is_capped_there():
    from calibration.decisions import widened_box
    assert widened_box({"name": "friction_pp", "low": 0.3, "high": 1.0}, "high") is None
    assert widened_box({"name": "friction_pw", "low": 0.2, "high": 0.8}, "high")["high"] == pytest.approx(1.0)
    assert widened_box({"name": "effects.rolling_epsd2.rolling_friction", "low": 0.0, "high": 0.5}, "high") is None


def test_a_box_is_widened_once():
    from calibration.decisions import widened_box
    first = {"name": "particle_stiffness_n_per_m", "low": 1.0e6, "high": 3.0e6}
    wider = widened_box(first, "high", first)
    assert wider["high"] == pytest.approx(5.0e6)
    assert widened_box(wider, "high", first) is None                     # that side was widened already
    assert widened_box(wider, "low", first)["low"] == pytest.approx(1.0e4)  # the other side has not been


def test_a_measured_parameter_pushed_away_from_its_measurement_keeps_its_box():
    """Particle density by water displacement, 2,586.5 kg/m3 +- 1 % (thesis Section 4.5.2): an edge at 2,700
    lies 4.4 sd from it, so the data pushing there contradict the measurement; an edge at 2,620 (1.3 sd) does not."""
    from calibration.decisions import widened_box
    from calibration.settings import PriorIn
    prior = PriorIn(parameter="particle_density_kg_m3", value=2586.5, uncertainty=25.865)
    rho = {"name": "particle_density_kg_m3", "low": 2300.0, "high": 2700.0}
    assert widened_box(rho, "high") is not None and widened_box(rho, "high", prior=prior) is None
    assert widened_box({**rho, "high": 2620.0}, "high", prior=prior)["high"] == pytest.approx(2940.0)
