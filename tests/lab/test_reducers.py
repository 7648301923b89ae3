"""Reducers on synthetic curves whose answers are known analytically."""
import math

import numpy as np
import pytest

from engine.lab.reducers import (
    PackingState,
    angle_of_repose,
    bulk_properties,
    dilatancy_angle_deg,
    mohr_coulomb_fit,
    moving_average,
    reduce_anchor,
    reduce_cct,
    reduce_dst,
    split_cycles,
    window_mean,
)


def test_bulk_properties_thesis_table_4_5_average():
    # Table 4.5: 125.8 kg in A*H with H = 0.329 m, A = pi 0.295^2; rho_p = 2586.5 (section 4.5.2)
    area = math.pi * 0.295**2
    rho_p = 2586.5
    state = PackingState(125.8 / rho_p, rho_p, 0.329, area, 100)
    props = bulk_properties(state)
    assert props["bulk_density_kg_m3"] == pytest.approx(125.8 / (area * 0.329))
    assert props["bulk_density_kg_m3"] == pytest.approx(1397.8, rel=0.01)
    assert props["voids_ratio"] == pytest.approx(0.85, abs=0.01)
    assert props["porosity"] == pytest.approx(0.459, abs=0.005)
    e = props["voids_ratio"]
    assert props["porosity"] == pytest.approx(e / (e + 1))


def test_packing_height_is_the_highest_centre_plus_the_material_s_own_radius():
    """Thesis section 4.5.4: H = the highest sphere's centre + its radius. Levelled grains' centres sit at or
    below the level (0.330 m); at a coarse resolution x 2 a 32.4 mm sphere at the level would give 362.4 mm, the
    material's own 16.2 mm sphere 346.2 mm: the rule takes the radius at the material's size."""
    from engine.lab.reducers.packing import packing_height_m

    z = np.array([0.300, 0.330, 0.310])
    r = np.array([0.0324, 0.0324, 0.0500])
    assert packing_height_m(z, r) == pytest.approx(0.3624)           # as measured: the highest sphere top
    assert packing_height_m(z, r, 2.0) == pytest.approx(0.346 + 0.0002)  # 0.330 + 0.0162
    assert packing_height_m(z, r, 2.0) < packing_height_m(z, r)
    # the top sphere, not the highest centre, when a larger sphere stands out further
    assert packing_height_m(np.array([0.33, 0.32]), np.array([0.01, 0.03])) == pytest.approx(0.35)
    with pytest.raises(ValueError):
        packing_height_m(z, r, 0.5)


def test_a_packing_struck_off_has_the_level_as_its_height():
    """A laboratory strikes the packing off with a straightedge at the level and takes the container's volume to
    it as the bulk volume (thesis Table 4.5: 329-330 mm for the 330 mm level); the thesis's DEM rule reads the
    highest sphere top instead (Table 4.10: 340 mm). Bulk density m / (A H) then differs by the ratio of the two
    heights, here 330 / 362.4 for the same packing."""
    from engine.lab.reducers.packing import read_packing_height_m

    z = np.array([0.300, 0.330, 0.310])
    r = np.array([0.0324, 0.0324, 0.0500])
    assert read_packing_height_m("struck_off", 0.330, z, r) == 0.330
    assert read_packing_height_m("highest_sphere_top", 0.330, z, r) == pytest.approx(0.3624)
    area, solid = 0.2734, 0.050
    struck = bulk_properties(PackingState(solid, 2586.5, 0.330, area, 10))
    thesis = bulk_properties(PackingState(solid, 2586.5, 0.3624, area, 10))
    assert struck["bulk_mass_kg"] == thesis["bulk_mass_kg"] == pytest.approx(solid * 2586.5)
    assert thesis["bulk_density_kg_m3"] / struck["bulk_density_kg_m3"] == pytest.approx(0.330 / 0.3624)
    with pytest.raises(ValueError, match="height rule"):
        read_packing_height_m("by eye", 0.330, z, r)


def test_bulk_properties_rejects_empty():
    with pytest.raises(ValueError):
        bulk_properties(PackingState(0.0, 2500, 0.3, 0.1, 0))


def _cyclic_record(modulus_pa, max_stress_pa, cycles, compaction_strain, n=200):
    """Loading at E' (after a softer first loading), unloading at 2 E', all exactly linear."""
    strain, stress = [], []
    eps0 = 0.0
    for c in range(cycles):
        e_load = modulus_pa / 3 if c == 0 else modulus_pa
        s = np.linspace(0, max_stress_pa, n)
        strain.extend(eps0 + s / e_load)
        stress.extend(s)
        top = eps0 + max_stress_pa / e_load
        s_un = np.linspace(max_stress_pa, 0, n)[1:]
        strain.extend(top - (max_stress_pa - s_un) / (2 * modulus_pa))
        stress.extend(s_un)
        eps0 = top - max_stress_pa / (2 * modulus_pa)
    return np.array(strain), np.array(stress)


def test_split_cycles_finds_each_loading_branch():
    strain, _ = _cyclic_record(5e6, 6.56e4, 4, 0.0)
    assert len(split_cycles(strain)) == 4


def test_cct_modulus_and_bulk_stiffness():
    e_true = 9.0e6
    strain, stress = _cyclic_record(e_true, 65.6e3, 4, 0.0)
    area, height = math.pi * 0.295**2, 0.34
    red = reduce_cct(strain, stress, area, height)
    assert red.modulus_per_cycle_pa[0] == pytest.approx(e_true / 3, rel=1e-6)
    assert red.confined_modulus_pa == pytest.approx(e_true, rel=1e-6)
    assert red.bulk_stiffness_n_per_m == pytest.approx(area / height * e_true, rel=1e-6)
    assert all(m == pytest.approx(e_true, rel=1e-6) for m in red.window_modulus_pa)


def test_cct_stress_windows_expose_nonlinear_loading():
    # Hertz-like loading: sigma = K eps^1.5, so the tangent modulus rises with stress
    k = 1e9
    strain, stress = [], []
    for c in range(3):
        eps = np.linspace(0, 0.01, 300)
        strain.extend(eps)
        stress.extend(k * eps**1.5)
        strain.extend(eps[::-1][1:])
        stress.extend(k * eps[::-1][1:] ** 1.5)
    red = reduce_cct(np.array(strain), np.array(stress), 1.0, 1.0)
    assert np.all(np.diff(red.window_modulus_pa) > 0)


def test_moving_average_keeps_lines_and_removes_alternating_noise():
    x = np.linspace(0, 1, 101)
    assert np.allclose(moving_average(3 * x + 1, 21), 3 * x + 1)
    noise = np.where(np.arange(101) % 2 == 0, 1.0, -1.0)
    assert np.max(np.abs(moving_average(noise, 21)[10:-10])) <= 1 / 21 + 1e-12
    with pytest.raises(ValueError):
        moving_average(x, 20)


def test_mohr_coulomb_exact_line():
    sigma = np.array([10.5e3, 24.0e3, 38.3e3, 52.4e3])
    phi, c = 35.0, 2.0e3
    tau = c + sigma * math.tan(math.radians(phi))
    fit = mohr_coulomb_fit(sigma, tau)
    assert fit.friction_angle_deg == pytest.approx(phi)
    assert fit.cohesion_pa == pytest.approx(c)
    assert fit.r2 == pytest.approx(1.0)


def test_mohr_coulomb_r2_drops_with_scatter():
    sigma = np.array([1.0, 2.0, 3.0, 4.0])
    fit = mohr_coulomb_fit(sigma, np.array([1.0, 3.0, 1.0, 3.0]))
    assert fit.r2 == pytest.approx(0.2)  # slope 0.4 explains 0.8 of 4.0 total sum of squares


def test_dst_window_and_dilatancy():
    diameter, area = 0.59, math.pi * 0.295**2
    ds = np.linspace(0, 0.07, 701)
    strain = ds / diameter
    # shear force rises then plateaus at 20 kN; lid contracts then dilates with slope tan(10 deg)
    tau_res = 20e3
    shear_force = area * tau_res * np.minimum(1.0, strain / 0.05)
    normal_force = np.full_like(ds, area * 24e3)
    turn = 0.02
    lid = np.where(ds < turn, -0.1 * ds, -0.1 * turn + math.tan(math.radians(10)) * (ds - turn))
    red = reduce_dst(ds, shear_force, normal_force, lid, area, diameter)
    assert red.residual_shear_stress_pa == pytest.approx(tau_res)
    assert red.residual_normal_stress_pa == pytest.approx(24e3)
    assert red.dilatancy_angle_deg == pytest.approx(10.0)
    assert window_mean(strain, strain, (0.08, 0.10)) == pytest.approx(0.09, abs=2e-4)


def test_dst_window_must_be_reached():
    ds = np.linspace(0, 0.03, 100)
    with pytest.raises(ValueError, match="residual window"):
        dilatancy_angle_deg(ds, ds, ds / 0.59)


def test_angle_of_repose_of_a_cone_of_spheres():
    # spheres of radius r stacked on a cone surface of slope 30 deg around (0.1, -0.2)
    r, alpha = 0.005, math.radians(30.0)
    pts = []
    for rho in np.arange(0.0, 0.3, r):
        for az in np.linspace(0, 2 * np.pi, 200, endpoint=False):
            h = max((0.3 - rho) * math.tan(alpha), 0.0)
            for z in np.arange(r, h + 1e-12 - r, 2 * r):
                pts.append((0.1 + rho * math.cos(az), -0.2 + rho * math.sin(az), z))
            if h >= 2 * r:
                pts.append((0.1 + rho * math.cos(az), -0.2 + rho * math.sin(az), h - r))
    pts = np.array(pts)
    red = angle_of_repose(pts, np.full(len(pts), r), centre_xy_m=(0.1, -0.2), bin_width_m=0.01)
    assert len(red.sector_angles_deg) == 8
    assert red.angle_of_repose_deg == pytest.approx(30.0, abs=1.0)
    assert all(a == pytest.approx(30.0, abs=1.5) for a in red.sector_angles_deg)


def test_anchor_peak():
    d = np.linspace(0, 0.1, 1001)
    f = 500 * np.exp(-((d - 0.01) / 0.005) ** 2) + 10
    red = reduce_anchor(d, f)
    assert red.peak_pull_force_n == pytest.approx(510)
    assert red.displacement_at_peak_m == pytest.approx(0.01)
