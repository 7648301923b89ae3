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
