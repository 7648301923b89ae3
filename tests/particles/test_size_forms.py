"""What a size form says of itself (engine.particles.distributions.number_cdf, bin_shares, described): the one
place the material card and the LIGGGHTS export read a distribution's shares and moments from."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from engine.particles import distributions as dist


def test_uniform_radii_fill_equal_bins_with_the_rectangle_s_moments():
    size = dist.UniformSize(0.019, 0.021)
    assert dist.bin_shares(size, np.linspace(0.019, 0.021, 5)) == pytest.approx([0.25] * 4)
    kind, mean, sd = dist.described(size)
    # a rectangle of width w: mean at its midpoint, sd w / sqrt(12)
    assert (kind, mean, sd) == ("uniform", pytest.approx(0.020), pytest.approx(0.002 / math.sqrt(12.0)))


def test_truncated_gaussian_shares_are_the_normal_s_renormalised_within_the_range():
    size = dist.TruncatedGaussian(0.0075, 0.0105)  # the thesis's pyramid class: mean 9 mm, sd 0.5 mm
    edges = np.array([0.0075, 0.0085, 0.0095, 0.0105])
    z = stats.norm.cdf((edges - 0.009) / 0.0005)   # -3, -1, +1, +3 sd
    expected = np.diff(z) / (z[-1] - z[0])
    assert dist.bin_shares(size, edges) == pytest.approx(expected)
    assert expected[1] == pytest.approx(0.6827 / 0.9973, abs=1e-4)  # the normal's +-1 sd within +-3 sd
    assert dist.number_cdf(size, [0.0075, 0.009, 0.0105]) == pytest.approx([0.0, 0.5, 1.0])
    assert dist.described(size) == ("truncated_gaussian", pytest.approx(0.009), pytest.approx(0.0005))


def test_a_sieve_curve_has_no_closed_form_and_is_described_by_its_draws():
    size = dist.SievePSD((0.008, 0.016), (0.0, 1.0))  # 8-16 mm, mass uniform in size: number ~ size^-3
    assert dist.number_cdf(size, [0.005]) is None
    edges = np.array([0.004, 0.006, 0.008])
    shares = dist.bin_shares(size, edges)
    # number density ~ d^-3 between 8 and 16 mm: the share below 12 mm is (8^-2 - 12^-2) / (8^-2 - 16^-2) = 20/27
    assert shares.sum() == pytest.approx(1.0)
    assert shares[0] == pytest.approx(20.0 / 27.0, abs=0.01)
    kind, mean, _ = dist.described(size)
    assert kind == "sampled" and 0.004 < mean < 0.006
