"""Random insertion: no overlaps, inside the region, reproducible; shape-mix and size statistics."""
import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.stats import truncnorm

from engine.particles import distributions as D
from engine.particles import generation as G
from engine.particles import templates as T


def overlaps_between_bodies(packing):
    c, r, body = packing.sphere_positions()
    pairs = cKDTree(c).query_pairs(2 * r.max(), output_type="ndarray")
    pairs = pairs[body[pairs[:, 0]] != body[pairs[:, 1]]]
    d = np.linalg.norm(c[pairs[:, 0]] - c[pairs[:, 1]], axis=1)
    return int((d < (r[pairs[:, 0]] + r[pairs[:, 1]]) * (1 - 1e-12)).sum())


def test_ten_thousand_spheres_in_a_cylinder_without_overlap():
    region = G.CylinderRegion(radius_m=0.279, z_min_m=0.005, z_max_m=1.6)
    tpls = [T.sphere(0.010), T.sphere(0.0125), T.sphere(0.015)]
    p = G.insert_random(tpls, np.arange(10_000) % 3, region, seed=7)
    assert p.n_bodies == 10_000
    assert overlaps_between_bodies(p) == 0
    c, r, _ = p.sphere_positions()
    assert np.all(np.hypot(c[:, 0], c[:, 1]) + r <= 0.279 + 1e-12)
    assert np.all(c[:, 2] - r >= 0.005 - 1e-12) and np.all(c[:, 2] + r <= 1.6 + 1e-12)
    np.testing.assert_allclose(np.linalg.norm(p.orientations, axis=1), 1, atol=1e-12)


def test_clumps_in_a_box_keep_their_shape_and_do_not_overlap():
    region = G.BoxRegion((0, 0, 0), (0.3, 0.3, 2.0))
    tpls = [T.pyramid(0.009), T.double_clump(0.013, 0.014, 0.7)]
    p = G.insert_random(tpls, np.arange(2000) % 2, region, seed=3)
    assert overlaps_between_bodies(p) == 0
    c, r, body = p.sphere_positions()
    assert np.all(c - r[:, None] >= -1e-12) and np.all(c + r[:, None] <= np.array([0.3, 0.3, 2.0]) + 1e-12)
    # rigid: world distances between a body's spheres equal the template's
    i = np.nonzero(body == 1)[0]
    d = np.linalg.norm(c[i[0]] - c[i[1]])
    assert d == pytest.approx(0.7 * 0.027, rel=1e-12)
    # orientations are random (not all identity)
    assert np.std(p.orientations[:, 0]) > 0.1


def test_same_seed_same_packing_and_block_size_does_not_matter():
    region = G.CylinderRegion(0.1, 0.0, 0.5)
    tpls = [T.sphere(0.01), T.double_clump(0.01, 0.008, 0.8)]
    idx = np.arange(400) % 2
    a = G.insert_random(tpls, idx, region, seed=11)
    b = G.insert_random(tpls, idx, region, seed=11, block=37)
    c = G.insert_random(tpls, idx, region, seed=12)
    np.testing.assert_array_equal(a.positions_m, b.positions_m)
    np.testing.assert_array_equal(a.orientations, b.orientations)
    assert not np.array_equal(a.positions_m, c.positions_m)


def test_too_full_region_raises_a_clear_error():
    region = G.BoxRegion((0, 0, 0), (0.1, 0.1, 0.1))
    with pytest.raises(G.InsertionError, match="region too full"):
        G.insert_random([T.sphere(0.01)], np.zeros(1000, int), region, seed=1, max_attempts=200)


def test_lattice_is_dense_and_non_overlapping():
    region = G.CylinderRegion(0.1, 0.0, 0.3)
    p = G.lattice(T.sphere(0.01), region, count=500)
    assert p.n_bodies == 500
    assert overlaps_between_bodies(p) == 0
    assert p.positions_m[:, 2].min() == pytest.approx(0.01)
    with pytest.raises(G.InsertionError):
        G.lattice(T.sphere(0.01), region, count=100_000)


def test_thesis_shape_mix_meets_volume_fractions_not_number_fractions():
    mix = D.thesis_shape_mix()
    region = G.BoxRegion((-0.1, -0.1, 0.1), (0.1, 0.1, 4.7))  # thesis generation volume (Fig. 4.9)
    p = G.generate(mix, region, seed=5, solid_volume_m3=0.03)
    comp = p.meta["component_index"]
    vol = np.array([t.volume_m3 for t in p.templates])
    share = np.array([vol[comp == k].sum() for k in range(3)]) / vol.sum()
    # the deficit rule meets each share to within one body's volume
    np.testing.assert_allclose(share, [0.375, 0.417, 0.208], atol=vol.max() / vol.sum())
    assert vol.sum() >= 0.03 and vol.sum() - 0.03 <= vol.max()
    counts = np.bincount(comp, minlength=3) / len(comp)
    assert abs(counts[0] - 0.375) > 0.05  # pyramids are small: their number share is far above 37.5 %
    assert overlaps_between_bodies(p) == 0
    # sphere radii of each component stay in the thesis Table 4.2 ranges
    for k, (lo, hi) in enumerate([(7.5e-3, 10.5e-3), (12e-3, 15e-3), (15e-3, 16.2e-3)]):
        r = np.concatenate([p.templates[i].sphere_radii_m for i in np.nonzero(comp == k)[0]])
        assert r.min() >= lo and r.max() <= hi


def test_truncated_gaussian_moments():
    dist = D.TruncatedGaussian(7.5e-3, 10.5e-3)
    r = dist.sample(np.random.default_rng(0), 200_000)
    mu, sd = 9e-3, 0.5e-3
    ref = truncnorm(-3, 3, loc=mu, scale=sd)
    assert abs(r.mean() - ref.mean()) < 4 * ref.std() / np.sqrt(r.size)
    assert r.std() == pytest.approx(ref.std(), rel=0.01)  # sd of a sample sd ~ 1/sqrt(2n) = 0.16 %
    assert r.min() >= 7.5e-3 and r.max() <= 10.5e-3


def test_sieve_psd_reproduces_the_mass_passing_curve():
    psd = D.SievePSD((0.010, 0.020, 0.030, 0.040), (0.0, 0.3, 0.8, 1.0))
    r = psd.sample(np.random.default_rng(1), 200_000)
    assert r.min() >= 0.005 and r.max() <= 0.020
    np.testing.assert_allclose(psd.mass_passing(r), [0.0, 0.3, 0.8, 1.0], atol=0.01)


def test_uniform_and_discrete_sizes():
    rng = np.random.default_rng(2)
    u = D.UniformSize(0.01, 0.02).sample(rng, 100_000)
    assert abs(u.mean() - 0.015) < 4 * (0.01 / np.sqrt(12)) / np.sqrt(u.size)
    d = D.DiscreteSizes((0.01, 0.0125, 0.015), (1, 1, 1)).sample(rng, 30_000)
    counts = np.array([(d == x).sum() for x in (0.01, 0.0125, 0.015)])
    assert np.all(np.abs(counts - 10_000) < 4 * np.sqrt(30_000 * (1 / 3) * (2 / 3)))


def test_bad_distribution_input_is_rejected():
    with pytest.raises(ValueError, match="r_min_m"):
        D.TruncatedGaussian(0.02, 0.01)
    with pytest.raises(ValueError, match="add up"):
        D.ShapeMix((D.ShapeComponent("sphere", D.ConstantSize(0.01), 0.5),))
    with pytest.raises(ValueError, match="cumulative_passing"):
        D.SievePSD((0.01, 0.02), (0.0, 0.9))
    with pytest.raises(ValueError, match="overlap_factor"):
        D.ShapeComponent("double_clump", D.ConstantSize(0.01), 1.0, overlap_factor=0.3)
