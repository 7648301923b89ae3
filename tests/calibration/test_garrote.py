"""The signature rows' shrinkage (``calibration.attribute.garrote``): the non-negative garrote
m max(0, 1 - se^2/m^2) of a mean m with the standard error se of the paired differences, on cases whose
answer is plain arithmetic, and its purpose checked by simulation: on pure noise it lowers the mean
squared error of the signature row against the raw mean, and a large effect keeps nearly all of itself."""
import numpy as np
import pytest

from calibration.attribute import garrote


def test_no_scatter_keeps_the_mean_and_one_pair_is_kept_as_it_is():
    assert garrote([2.0, 2.0, 2.0]) == 2.0
    assert garrote([5.0]) == 5.0


def test_the_garrote_by_hand():
    # m = 2, sample variance 1, se^2 = 1/3: 2 (1 - (1/3)/4) = 11/6
    assert garrote([1.0, 2.0, 3.0]) == pytest.approx(11.0 / 6.0, rel=1e-12)
    assert garrote([-1.0, -2.0, -3.0]) == pytest.approx(-11.0 / 6.0, rel=1e-12)
    # m = 0.1, sample variance 1.21, se^2 = 0.4033 > m^2: within its scatter, so zero
    assert garrote([1.2, -1.0, 0.1]) == 0.0
    assert garrote([1.0, -1.0, 0.0]) == 0.0


def test_noise_shrinks_and_a_large_effect_stays():
    rng = np.random.default_rng(20261124)
    noise = rng.standard_normal((20000, 3))
    raw = noise.mean(axis=1)
    shrunk = np.array([garrote(row) for row in noise])
    # a row the effect does not move: the raw mean's MSE is 1/3; the garrote's is well below it
    assert np.mean(shrunk ** 2) < 0.5 * np.mean(raw ** 2)
    # an effect of 10 standard errors (se = 1/sqrt 3): kept within 2 % on average
    big = 10.0 / np.sqrt(3.0) + noise
    assert np.mean([garrote(row) for row in big]) == pytest.approx(10.0 / np.sqrt(3.0), rel=0.02)
