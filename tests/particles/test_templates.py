"""Clump mass properties against analytic values and independent Monte Carlo integration."""
import numpy as np
import pytest

from engine.particles import templates as T


def lens_eq_4_9(r1, r2, d):
    """Thesis Eq. 4.9, transcribed independently of the engine."""
    return np.pi / (12 * d) * (r1 + r2 - d) ** 2 * (d * d + 2 * d * r2 - 3 * r2**2 + 2 * d * r1 + 6 * r2 * r1 - 3 * r1**2)


def mc_moments(centres, radii, n=1_000_000, seed=12345):
    """Monte Carlo V, int x dV, int r r^T dV of a sphere union, with standard errors (fixed seed)."""
    rng = np.random.default_rng(seed)
    lo = (centres - radii[:, None]).min(0)
    hi = (centres + radii[:, None]).max(0)
    box = np.prod(hi - lo)
    p = lo + (hi - lo) * rng.random((n, 3))
    inside = np.zeros(n, bool)
    for c, r in zip(centres, radii):
        inside |= ((p - c) ** 2).sum(1) < r * r
    f = inside.astype(float)

    def est(g):
        return box * g.mean(), box * g.std() / np.sqrt(n)

    out = {"V": est(f)}
    for i in range(3):
        out[f"m{i}"] = est(f * p[:, i])
        for j in range(3):
            out[f"s{i}{j}"] = est(f * p[:, i] * p[:, j])
    return out


def test_two_separate_spheres_match_parallel_axis_theorem():
    r1, r2, gap = 0.01, 0.015, 0.004
    d = r1 + r2 + gap
    t = T.from_spheres(np.array([[0, 0, 0], [d, 0, 0.0]]), np.array([r1, r2]))
    rho = 2500.0
    v1, v2 = 4 / 3 * np.pi * r1**3, 4 / 3 * np.pi * r2**3
    m1, m2 = rho * v1, rho * v2
    assert t.mass_kg(rho) == pytest.approx(m1 + m2, rel=1e-12)
    xc = m2 * d / (m1 + m2)
    axial = 0.4 * m1 * r1**2 + 0.4 * m2 * r2**2
    transverse = axial + m1 * xc**2 + m2 * (d - xc) ** 2
    np.testing.assert_allclose(t.principal_inertia_kg_m2(rho), [axial, transverse, transverse], rtol=1e-12)
    # principal frame: centre of mass at the origin, the clump axis along body x
    com = (v1 * t.sphere_offsets_m[0] + v2 * t.sphere_offsets_m[1]) / (v1 + v2)
    np.testing.assert_allclose(com, 0, atol=1e-15)
    np.testing.assert_allclose(np.abs(t.sphere_offsets_m[:, 0]), [xc, d - xc], rtol=1e-12)
    np.testing.assert_allclose(t.sphere_offsets_m[:, 1:], 0, atol=1e-15)


def test_touching_double_clump_c1_has_no_lens():
    r = 0.0135
    t = T.double_clump(r, r, 1.0)
    assert t.volume_m3 == pytest.approx(2 * 4 / 3 * np.pi * r**3, rel=1e-12)
    m = 4 / 3 * np.pi * r**3
    np.testing.assert_allclose(t.principal_inertia_per_density_m5, [0.8 * m * r * r, 0.8 * m * r * r + 2 * m * r * r,
                                                                   0.8 * m * r * r + 2 * m * r * r], rtol=1e-12)


def test_lens_volume_limits_and_half_overlap():
    r = 0.01
    assert T.lens_volume_m3(r, r, 2 * r) == 0.0
    # one sphere inside the other: the lens is the smaller sphere
    assert T.lens_volume_m3(r, 0.5 * r, 0.1 * r) == pytest.approx(4 / 3 * np.pi * (0.5 * r) ** 3, rel=1e-12)
    # coincident equal spheres: the whole sphere
    assert T.lens_volume_m3(r, r, 1e-12) == pytest.approx(4 / 3 * np.pi * r**3, rel=1e-5)
    # equal spheres at distance d: pi/12 (4r + d)(2r - d)^2
    assert T.lens_volume_m3(r, r, r) == pytest.approx(np.pi / 12 * (4 * r + r) * (2 * r - r) ** 2, rel=1e-12)


@pytest.mark.parametrize("r1,r2,c", [(0.01, 0.01, 0.5), (0.012, 0.015, 0.7), (0.015, 0.009, 0.55)])
def test_overlapping_double_clump_volume_and_inertia(r1, r2, c):
    d = c * (r1 + r2)
    t = T.double_clump(r1, r2, c)
    v_exact = 4 / 3 * np.pi * (r1**3 + r2**3) - lens_eq_4_9(r1, r2, d)
    assert t.volume_m3 == pytest.approx(v_exact, rel=1e-12)
    assert T.lens_volume_m3(r1, r2, d) == pytest.approx(lens_eq_4_9(r1, r2, d), rel=1e-12)

    centres = np.array([[0, 0, 0], [d, 0, 0.0]])
    mc = mc_moments(centres, np.array([r1, r2]))
    (v, sv) = mc["V"]
    assert abs(t.volume_m3 - v) < 4 * sv
    # the template's sphere 1 sits at -xc on the body x axis: move its inertia back to sphere 1's centre
    xc = -t.sphere_offsets_m[0, 0]
    axial = t.principal_inertia_per_density_m5[0]
    transverse = t.principal_inertia_per_density_m5[1] + t.volume_m3 * xc**2
    s_yy, e_yy = mc["s11"]
    s_zz, e_zz = mc["s22"]
    s_xx, e_xx = mc["s00"]
    assert abs(axial - (s_yy + s_zz)) < 4 * np.hypot(e_yy, e_zz)
    assert abs(transverse - (s_xx + s_yy)) < 4 * np.hypot(e_xx, e_yy)
    # and the centre of mass
    m0, e0 = mc["m0"]
    assert abs(xc * t.volume_m3 - m0) < 4 * e0


def test_triple_overlap_uses_integration_and_matches_monte_carlo():
    centres = np.array([[0, 0, 0], [0.015, 0, 0], [0.0075, 0.011, 0.004]])
    radii = np.array([0.01, 0.011, 0.009])
    v, com, inertia, method = T.union_mass_properties(centres, radii)
    assert method.startswith("columns")
    mc = mc_moments(centres, radii, n=2_000_000)
    assert abs(v - mc["V"][0]) < 4 * mc["V"][1]
    s = np.array([[mc[f"s{i}{j}"][0] for j in range(3)] for i in range(3)])
    e = np.array([[mc[f"s{i}{j}"][1] for j in range(3)] for i in range(3)])
    # inertia about the origin from the template's values: I_o = I_com + V (|c|^2 1 - c c^T)
    i_origin = inertia + v * (com @ com * np.eye(3) - np.outer(com, com))
    i_mc = np.trace(s) * np.eye(3) - s
    for a in range(3):
        b, c = (a + 1) % 3, (a + 2) % 3
        assert abs(i_origin[a, a] - i_mc[a, a]) < 4 * np.hypot(e[b, b], e[c, c])


def test_integration_route_agrees_with_exact_route_on_pairwise_overlaps():
    centres = np.array([[0, 0, 0], [0.016, 0.003, -0.002]])
    radii = np.array([0.01, 0.012])
    v_ex, com_ex, i_ex, method = T.union_mass_properties(centres, radii)
    assert method == "exact"
    v, first, s = T._moments_columns(centres, radii, 512)
    com, inertia = T._inertia_about_com(v, first, s)
    assert v == pytest.approx(v_ex, rel=2e-4)
    np.testing.assert_allclose(com, com_ex, atol=1e-3 * radii.min())
    np.testing.assert_allclose(inertia, i_ex, atol=3e-4 * np.abs(i_ex).max())


def test_pyramid_is_isotropic_with_analytic_inertia():
    r = 0.009
    t = T.pyramid(r)
    m = 4 / 3 * np.pi * r**3  # per unit density
    assert t.volume_m3 == pytest.approx(4 * m, rel=1e-9)  # touching spheres: no overlap
    # 4 (2/5 m r^2) + sum over spheres of m (d^2 - d_a^2): d^2 = 3 r^2 / 2, isotropic -> (2/3) d^2 each
    np.testing.assert_allclose(t.principal_inertia_per_density_m5, 5.6 * m * r * r, rtol=1e-9)
    d = np.linalg.norm(t.sphere_offsets_m[:, None] - t.sphere_offsets_m[None], axis=2)
    np.testing.assert_allclose(d[~np.eye(4, dtype=bool)], 2 * r, rtol=1e-12)


@pytest.mark.parametrize("c", [0.49, 1.01, float("nan"), -1.0])
def test_overlap_factor_out_of_range_is_rejected(c):
    with pytest.raises(ValueError, match="overlap_factor"):
        T.double_clump(0.01, 0.01, c)


def test_bad_sphere_sets_are_rejected():
    with pytest.raises(ValueError, match="radius"):
        T.from_spheres(np.zeros((2, 3)), np.array([0.01, -0.01]))
    with pytest.raises(ValueError, match="shape"):
        T.from_spheres(np.zeros((2, 2)), np.array([0.01, 0.01]))


def test_principal_values_do_not_depend_on_input_frame_and_scale_as_length_to_the_fifth():
    centres = np.array([[0, 0, 0], [0.015, 0, 0], [0.0, 0.02, 0.01], [0.03, 0.02, 0.0]])
    radii = np.array([0.01, 0.008, 0.009, 0.011])
    a = T.from_spheres(centres, radii)
    rng = np.random.default_rng(0)
    q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    b = T.from_spheres(centres @ q.T + [1.0, -2.0, 0.5], radii)
    assert b.volume_m3 == pytest.approx(a.volume_m3, rel=1e-12)
    np.testing.assert_allclose(b.principal_inertia_per_density_m5, a.principal_inertia_per_density_m5, rtol=1e-9)
    s = a.scaled(2.0)
    assert s.volume_m3 == pytest.approx(8 * a.volume_m3, rel=1e-12)
    np.testing.assert_allclose(s.principal_inertia_per_density_m5, 32 * a.principal_inertia_per_density_m5, rtol=1e-12)
    # offsets really are in the principal frame: the second-moment tensor of the body is diagonal there
    v, com, inertia, _ = T.union_mass_properties(a.sphere_offsets_m, a.sphere_radii_m)
    np.testing.assert_allclose(com, 0, atol=1e-12)
    off = inertia - np.diag(np.diag(inertia))
    assert np.abs(off).max() < 1e-9 * np.abs(inertia).max()
