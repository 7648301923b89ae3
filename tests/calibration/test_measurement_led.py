"""Which measured parameters an anchor holds (``calibration.calibrate.measurement_led``), on whitened linear cases
whose information is known by hand.

A measured parameter is held at its measurement where that measurement carries more information about it than
the targets do once the other free parameters have traded against it (the Schur complement of J_t^T J_t).
"""
from types import SimpleNamespace

import numpy as np

from calibration.calibrate import measurement_led

NAMES = ["particle_density_kg_m3", "friction_pp", "friction_pw"]


def _residuals(target_rows, prior_sds_coded):
    """Targets' whitened rows of J, then one prior row per parameter: d r / d u = -1 / sd (coded units), so the
    prior's information is 1 / sd^2."""
    prior_rows = [-np.eye(len(NAMES))[j] / sd for j, sd in enumerate(prior_sds_coded)]
    return SimpleNamespace(keys=list(range(len(target_rows))), J=np.array(list(target_rows) + prior_rows),
                           free=list(NAMES), prior_names=list(NAMES))


def test_parameters_that_trade_perfectly_are_led_by_their_measurements_and_a_pinned_one_by_its_target():
    # a bulk density fixes the density (information 10^2 = 100 against the pycnometer's 1 / 0.5^2 = 4); one
    # shear strength sees only pp + pw, so J_t^T J_t on the frictions is [[4, 4], [4, 4]] and each one's
    # marginal information is 4 - 4 x 4 / 4 = 0, below its tilt test's 1
    res = _residuals([[10.0, 0.0, 0.0], [0.0, 2.0, 2.0]], [0.5, 1.0, 1.0])
    assert measurement_led(res) == ["friction_pp", "friction_pw"]


def test_a_measurement_tighter_than_the_target_leads():
    # the same targets, the pycnometer now to 0.05 coded units: information 400 against the bulk density's 100
    res = _residuals([[10.0, 0.0, 0.0], [0.0, 2.0, 2.0]], [0.05, 1.0, 1.0])
    assert measurement_led(res) == NAMES


def test_a_second_target_that_separates_the_frictions_takes_the_lead_from_their_tilt_tests():
    # a wall-friction test sees pw alone (row [0, 0, 3]): J_t^T J_t on the frictions is [[4, 4], [4, 13]];
    # pp's marginal information is 4 - 16 / 13 = 2.77, pw's 13 - 16 / 4 = 9, both above their tilt tests' 1
    res = _residuals([[10.0, 0.0, 0.0], [0.0, 2.0, 2.0], [0.0, 0.0, 3.0]], [0.5, 1.0, 1.0])
    assert measurement_led(res) == []
    # with the tilt tests to 0.5 coded units (information 4), pp's 2.77 falls below its measurement's; pw's 9 does not
    res = _residuals([[10.0, 0.0, 0.0], [0.0, 2.0, 2.0], [0.0, 0.0, 3.0]], [0.5, 0.5, 0.5])
    assert measurement_led(res) == ["friction_pp"]
