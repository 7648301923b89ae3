"""Design construction: factors, fractions, centre runs and seeds, run order, fold-over, CCD."""
import numpy as np
import pytest

from doe import (Design, DoeError, Factor, augment_ccd, foldover, fractional_factorial, full_factorial,
                 make_design)
from doe.terms import model_matrix

FOUR = [("rho_p", 2000, 20000, "kg/m3"), ("mu_pp", 0.05, 0.5), ("mu_pw", 0.01, 0.045), ("k_p", 1e6, 2e6, "N/m")]


def test_coded_natural_round_trip_and_log_scale():
    f = Factor("k_n", 1e5, 1e7, "N/m", log=True)
    assert f.centre == pytest.approx(1e6)               # geometric mean of the levels
    assert f.to_coded(1e6) == pytest.approx(0.0)
    assert f.to_natural(-1.0) == 1e5 and f.to_natural(1.0) == 1e7
    g = Factor("mu", 0.2, 0.6)
    x = np.array([0.2, 0.3, 0.55])
    np.testing.assert_allclose(g.to_natural(g.to_coded(x)), x)
    with pytest.raises(DoeError, match="below high"):
        Factor("bad", 1, 1)
    with pytest.raises(DoeError, match="positive"):
        Factor("bad", 0, 1, log=True)


@pytest.mark.parametrize("k,gens,res", [(5, ["D=AB", "E=AC"], 3), (5, ["E=ABCD"], 5), (6, ["E=ABC", "F=BCD"], 4),
                                        (7, ["D=AB", "E=AC", "F=BC", "G=ABC"], 3)])
def test_resolution_matches_shortest_defining_word(k, gens, res):
    d = fractional_factorial([(f"x{i}", 0, 1) for i in range(k)], gens, randomize=False)
    assert d.n_runs == 2 ** (k - len(gens))
    assert d.aliases.resolution == res
    # every defining word is constant over the runs, and there are 2^p - 1 of them
    assert len(d.aliases.defining_relation) == 2 ** len(gens) - 1
    # balanced and orthogonal main-effect columns
    X = d.coded
    np.testing.assert_allclose(X.T @ X, d.n_runs * np.eye(k))


def test_negative_generator_and_bad_generators():
    d = fractional_factorial(FOUR, ["D=-ABC"], randomize=False)
    np.testing.assert_array_equal(d.coded[:, 3], -np.prod(d.coded[:, :3], axis=1))
    assert d.aliases.defining_relation == [("ABCD", -1)]
    for bad, msg in [(["D=ABX"], "unknown factor letter"), (["D=A"], "two or more"), (["ABC"], "form D=ABC"),
                     (["D=ABC", "C=AB"], "base factors only")]:
        with pytest.raises(DoeError, match=msg):
            fractional_factorial(FOUR, bad)


def test_centre_runs_replicates_seeds_and_run_order():
    d = make_design(FOUR, center_runs=4, replicates=2, seed=7)
    assert d.n_runs == 8 * 2 + 4
    assert d.center_mask.sum() == 4
    assert len(set(d.seed.tolist())) == d.n_runs              # every run its own simulator seed
    assert sorted(d.run_order.tolist()) == list(range(1, d.n_runs + 1))
    np.testing.assert_array_equal(d.std_order, np.arange(1, d.n_runs + 1))
    assert sorted(d.replicate[d.center_mask].tolist()) == [1, 2, 3, 4]
    assert set(d.replicate[d.factorial_mask].tolist()) == {1, 2}
    same = make_design(FOUR, center_runs=4, replicates=2, seed=7)
    other = make_design(FOUR, center_runs=4, replicates=2, seed=8)
    np.testing.assert_array_equal(d.run_order, same.run_order)
    np.testing.assert_array_equal(d.seed, same.seed)
    assert not np.array_equal(d.run_order, other.run_order)
    recs = d.records("run")
    assert [r["run_order"] for r in recs] == list(range(1, d.n_runs + 1))
    assert {"std_order", "run_order", "seed", "point_type", "rho_p", "A_coded"} <= set(recs[0])


def test_design_dict_round_trip():
    d = augment_ccd(make_design(FOUR, center_runs=2, seed=3), "face")
    e = Design.from_dict(d.to_dict())
    np.testing.assert_allclose(e.coded, d.coded)
    np.testing.assert_array_equal(e.seed, d.seed)
    np.testing.assert_array_equal(e.run_order, d.run_order)
    assert e.point_type == d.point_type and e.generators == d.generators


def test_single_factor_foldover_dealiases_that_factor():
    """Folding a resolution III 2^(7-4) on A frees A and every 2FI with A (Montgomery, DAE, 8.6)."""
    d = fractional_factorial([(f"x{i}", 0, 1) for i in range(7)], ["D=AB", "E=AC", "F=BC", "G=ABC"],
                             randomize=False)
    assert any(w == "BD" for w, _ in d.aliases.chain_of(0b1).aliases)   # A = BD before
    f = foldover(d, "x0")
    assert f.n_runs == 16 and set(f.block.tolist()) == {1, 2}
    chain_a = f.aliases.chain_of(0b1)
    assert min(len(w) for w, _ in chain_a.aliases) >= 3
    for j in range(1, 7):
        chain = f.aliases.chain_of(0b1 | 1 << j)
        assert all(len(w) >= 3 for w, _ in chain.aliases), chain.label
    assert len(set(f.seed.tolist())) == 16
    with pytest.raises(DoeError, match="already a full factorial"):
        foldover(full_factorial(FOUR[:2]), "rho_p")


def test_ccd_axial_points_and_rotatability():
    d2 = full_factorial([("a", 0, 1), ("b", 0, 1)], randomize=False)
    face = augment_ccd(d2, "face", center_runs=3)
    ax = face.coded[[t == "axial" for t in face.point_type]]
    assert ax.shape == (4, 2) and np.all(np.abs(ax).sum(axis=1) == 1.0)
    rot = augment_ccd(d2, "rotatable", center_runs=5)
    alpha = np.abs(rot.coded[[t == "axial" for t in rot.point_type]]).max()
    assert alpha == pytest.approx(np.sqrt(2))               # (n_F)^(1/4) with n_F = 4
    # rotatable: prediction variance of the quadratic model depends on the radius only
    terms = [(1, 0), (0, 1), (1, 1), (2, 0), (0, 2)]
    X = model_matrix(rot.coded, terms)
    inv = np.linalg.inv(X.T @ X)
    var = [float(model_matrix([[np.cos(t), np.sin(t)]], terms)[0] @ inv @ model_matrix([[np.cos(t), np.sin(t)]],
                                                                                       terms)[0])
           for t in np.linspace(0, np.pi / 2, 7)]
    assert np.ptp(var) < 1e-12
    assert len(set(rot.seed.tolist())) == rot.n_runs
    with pytest.raises(DoeError, match="already has axial"):
        augment_ccd(rot)


def test_rotatable_alpha_for_half_fraction_uses_its_own_runs():
    d = make_design(FOUR, seed=1)
    c = augment_ccd(d, "rotatable")
    assert np.abs(c.coded[[t == "axial" for t in c.point_type]]).max() == pytest.approx(8 ** 0.25)
    assert any("resolution 4" in n for n in c.notes)
