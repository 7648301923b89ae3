"""A settled column in a cylinder: the wall's normal stress against depth follows Janssen's law.

Janssen: a horizontal slice is held by the wall's friction, tau = mu_w sigma_h, with sigma_h = K sigma_v,
so sigma_v(z) = rho_b g D / (4 mu_w K) (1 - exp(-4 mu_w K z / D)) and the wall stress saturates at
rho_b g D / (4 mu_w) (z depth below the free surface, D the diameter, rho_b the bulk density).

How the columns are made to meet Janssen's assumptions:

* Wall friction fully mobilised, in one direction. After pouring and levelling, the tubes slide upward
  at 10 mm/s (0.5 mm before measuring, 1.5 mm while measuring; a contact slips after a few microns),
  so every wall contact slides (or its sphere rolls) upward relative to the material and the wall
  shear sits at its steady limit, pointing up, at every depth. A static wall leaves each contact with
  whatever tangential spring the settling gave it (partly mobilised, in either direction); lowering the
  floor instead unloads the column, which then arches. Spheres roll against a moving wall, so the
  interface's macroscopic friction (total upward shear / total normal force on the wall, measured) is
  below the contact coefficient: that ratio is Janssen's mu_w, and test_wall_friction_mobilised_uniformly
  checks it is the same at every depth.
* Gentle filling: batches of six layers dropped from just above the surface. Dropping a whole column at
  once locked in horizontal stresses above the vertical ones (K > 2, a passive state).
* No local (Cundall) damping: it acts like a drag to the ground on the slowly creeping material and took
  3 % of the weight (10 % of the floor load) out of the force balance. Viscous contact damping only.
* A frictionless floor: Janssen's slices have no base boundary layer; a frictional floor held the bottom
  layers' lateral strain and lowered the wall stress over the lowest half diameter.
* rho_b and the free surface come from the packing: solid fraction of a bulk slab (exact sphere-cap
  volumes) and the Gibbs dividing surface (the flat top that would hold the solid lying above the slab).

K, Janssen's one free parameter, is fitted to the wall profile (least squares on stresses); then (a) every
depth bin must be within 15 % of Janssen, (b) the floor load Janssen predicts with that K must be within
15 % of the measured one, (c) K must be physical, and (d) the column must saturate: the deepest wall stress
under half the hydrostatic K rho_b g z and the floor carrying under half the weight. (d) makes a
frictionless (hydrostatic) column fail whatever K comes out; test_hydrostatic_column_fails checks that.

Three columns (D = 12 mean diameters, H = 3.4 D, about 4,800 spheres each) are poured side by side in one
simulation and pooled: the force network next to a sliding wall is frozen, so averaging one wall over time
leaves about +-10 % per depth bin; three walls bring it to about +-5 %.
"""
import math

import numpy as np
import pytest

from engine.config import CylinderGeom, PlaneGeom, WallSpec
from engine.simulation import Simulation

import janssen_column as jc
from engine_helpers import G, config

RADIUS_MEAN_M = 0.002
RADIUS_MIN_M, RADIUS_MAX_M = 0.8 * RADIUS_MEAN_M, 1.2 * RADIUS_MEAN_M
CYLINDER_RADIUS_M = 12 * RADIUS_MEAN_M          # D = 12 mean diameters
DIAMETER_M = 2 * CYLINDER_RADIUS_M
FILL_HEIGHT_M = 3.4 * DIAMETER_M                # about three Janssen lengths: saturated at the bottom
N_COLUMNS = 3
DENSITY_KG_M3 = 2500.0
WALL_FRICTION = 0.4
PARTICLE_FRICTION = 0.7
MEASURE_WALL_SPEED_M_S = 0.01
N_BINS = 5
# K above Rankine's active ratio for a friction angle of atan(mu_p) (a sphere packing is weaker than its
# contacts, so this is a true floor) and below 1.5, well under any passive ratio (> 2 beyond 20 deg):
# a gently poured column is not in a passive state
K_RANGE = (jc.rankine_active_ratio(math.atan(PARTICLE_FRICTION)), 1.5)


def _centres():
    pitch = 2 * CYLINDER_RADIUS_M + 4 * RADIUS_MAX_M
    return np.array([(k * pitch, 0.0) for k in range(N_COLUMNS)])


def _build():
    # soft contacts (overlaps about 1 % of a radius at the bottom) for a long step; no tangential dashpot,
    # so a sliding contact carries exactly mu fn; no local damping (see the module docstring)
    sim = Simulation(config(mat_density_kg_m3=DENSITY_KG_M3, mat_normal_stiffness_n_per_m=1e3,
                            mat_friction=PARTICLE_FRICTION, mat_damping_ratio_normal=0.5,
                            mat_damping_ratio_shear=0.0, mat_local_damping=0.0, threads=1, record_every=20))
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), normal_stiffness_n_per_m=1e5, friction=0.0))
    for k, (cx, cy) in enumerate(_centres()):
        sim.add_wall(WallSpec(name=f"tube{k}", normal_stiffness_n_per_m=1e5, friction=WALL_FRICTION,
                              geometry=CylinderGeom(base_m=(cx, cy, -0.05), radius_m=CYLINDER_RADIUS_M,
                                                    height_m=1.0)))
    return sim


def run_columns(seed: int = 2026) -> dict:
    """Pour, level, slide the walls and measure; returns the comparison and the raw measurements."""
    sim = _build()
    centres = _centres()
    rng = np.random.default_rng(seed)
    jc.pour_in_layers(sim, centres, CYLINDER_RADIUS_M, RADIUS_MIN_M, RADIUS_MAX_M,
                      FILL_HEIGHT_M + 2 * RADIUS_MEAN_M, rng)
    sim.run(duration_s=0.05)
    sim.remove_bodies(sim.positions_m()[:, 2] > FILL_HEIGHT_M)  # level the tops
    sim.run(duration_s=0.1)

    pos, radii = sim.sphere_positions_m(), sim.sphere_radii_m()
    column = jc.column_of_spheres(pos, centres, CYLINDER_RADIUS_M)
    assert np.all(column >= 0)
    area = math.pi * CYLINDER_RADIUS_M ** 2
    profiles, geometry = [], []
    for k, c in enumerate(centres):
        sel = column == k
        geo = jc.measure_column(pos[sel, 2], radii[sel], area, 0.2 * FILL_HEIGHT_M, 0.8 * FILL_HEIGHT_M)
        geometry.append(geo)
        profiles.append(jc.WallStressProfile(f"tube{k}", tuple(c), CYLINDER_RADIUS_M, geo.surface_height_m,
                                             np.linspace(0.0, geo.surface_height_m, N_BINS + 1), WALL_FRICTION))
        sim.set_wall_velocity(f"tube{k}", (0.0, 0.0, MEASURE_WALL_SPEED_M_S))

    sim.run(duration_s=0.05)  # the wall slides 0.5 mm: every contact reaches its steady state
    sim.clear_wall_history()
    for _ in range(10):
        sim.run(duration_s=0.015)
        for p in profiles:
            p.sample(sim)
    floor_n = -float(np.mean(sim.wall_history("floor")["force_n"][:, 2]))
    tubes_up_n = -sum(float(np.mean(sim.wall_history(f"tube{k}")["force_n"][:, 2])) for k in range(N_COLUMNS))
    wall_friction = sum(p.shear_up_force_sum_n.sum() for p in profiles) / sum(
        p.normal_force_sum_n.sum() for p in profiles)
    weight = float(sim.body_masses_kg().sum()) * G
    columns = [jc.ColumnMeasurement(p.depth_edges_m, p.mean_normal_force_n, DENSITY_KG_M3 * g.solid_fraction,
                                    g.surface_height_m) for p, g in zip(profiles, geometry)]
    cmp = jc.compare_with_janssen(columns, CYLINDER_RADIUS_M, wall_friction, G, floor_n, weight)
    return {"cmp": cmp, "profiles": profiles, "geometry": geometry, "wall_friction": wall_friction,
            "floor_n": floor_n, "tubes_up_n": tubes_up_n, "weight_n": weight, "n_spheres": sim.n_spheres}


@pytest.fixture(scope="module")
def column_run():
    return run_columns()


@pytest.mark.slow
def test_wall_stress_follows_janssen(column_run):
    cmp = column_run["cmp"]
    failures = jc.acceptance_failures(cmp, K_RANGE)
    assert not failures, (failures, column_run["wall_friction"], cmp)


@pytest.mark.slow
def test_wall_friction_mobilised_uniformly(column_run):
    """Janssen's premise: tau = mu_w sigma_h with one mu_w at every depth, the wall holding the material up.

    Walls left static after the pour fail this (2 % of contacts at the Coulomb limit, mobilised ratio from
    -0.06 near the top to 0.29 deep); slid upward, 71 % slide and the ratio is 0.27-0.32 at every depth
    (slightly lower in the loosely held top bin).
    """
    profiles, mu = column_run["profiles"], column_run["wall_friction"]
    by_bin = sum(p.shear_up_force_sum_n for p in profiles) / sum(p.normal_force_sum_n for p in profiles)
    assert np.all(np.abs(by_bin / mu - 1.0) < 0.2), by_bin
    assert 0.5 * WALL_FRICTION < mu <= WALL_FRICTION  # the macroscopic ratio cannot exceed the contacts'
    sliding = sum(p.sliding_count.sum() for p in profiles) / sum(p.contact_count.sum() for p in profiles)
    assert sliding > 0.5, sliding


@pytest.mark.slow
def test_column_in_equilibrium_and_bulk_density_physical(column_run):
    """The instruments balance: floor load + upward wall friction = weight (time averages)."""
    total = column_run["floor_n"] + column_run["tubes_up_n"]
    assert abs(total / column_run["weight_n"] - 1.0) < 0.03
    for g in column_run["geometry"]:
        assert 0.5 < g.solid_fraction < 0.64  # random packing of frictional spheres, below random close packing
        assert abs(g.surface_height_m - FILL_HEIGHT_M) < 2 * RADIUS_MAX_M


def test_hydrostatic_column_fails():
    """Without wall friction sigma_h = K rho_b g z and the floor carries the weight: the rule must reject it,
    whatever K and mu_w the analysis is handed."""
    rho_b, h = 1370.0, FILL_HEIGHT_M
    edges = np.linspace(0.0, h, N_BINS + 1)
    band_area = 2 * math.pi * CYLINDER_RADIUS_M * np.diff(edges)
    weight = rho_b * G * math.pi * CYLINDER_RADIUS_M ** 2 * h
    for k_true in (0.4, 0.7, 1.0):
        stress = k_true * rho_b * G * 0.5 * (edges[:-1] + edges[1:])
        col = jc.ColumnMeasurement(edges, stress * band_area, rho_b, h)
        for mu in (0.2, 0.4):
            cmp = jc.compare_with_janssen([col], CYLINDER_RADIUS_M, mu, G, weight, weight)
            assert jc.acceptance_failures(cmp, K_RANGE)


def test_janssen_column_reproduces_itself():
    """The rule accepts Janssen's own profile and floor load (so it is not rejecting everything)."""
    rho_b, h, mu, k = 1370.0, FILL_HEIGHT_M, 0.26, 0.9
    edges = np.linspace(0.0, h, N_BINS + 1)
    band_area = 2 * math.pi * CYLINDER_RADIUS_M * np.diff(edges)
    stress = jc.janssen_band_mean_wall_stress_pa(edges[:-1], edges[1:], rho_b, G, DIAMETER_M, mu, k)
    base = jc.janssen_base_load_n(h, rho_b, G, DIAMETER_M, mu, k)
    weight = rho_b * G * math.pi * CYLINDER_RADIUS_M ** 2 * h
    cmp = jc.compare_with_janssen([jc.ColumnMeasurement(edges, stress * band_area, rho_b, h)], CYLINDER_RADIUS_M,
                                  mu, G, base, weight)
    assert jc.acceptance_failures(cmp, K_RANGE) == []
    assert cmp.lateral_ratio == pytest.approx(k, rel=1e-4)
    # Janssen's floor load is what the wall friction leaves of the weight (two separate formulas agree)
    friction = mu * math.pi * DIAMETER_M * h * float(
        jc.janssen_band_mean_wall_stress_pa(0.0, h, rho_b, G, DIAMETER_M, mu, k))
    assert base == pytest.approx(weight - friction, rel=1e-9)


if __name__ == "__main__":  # figures: cd tests/engine && python3 test_janssen.py [seed]
    import sys
    import time

    t0, c0 = time.perf_counter(), time.process_time()
    r = run_columns(*(int(a) for a in sys.argv[1:2]))
    c = r["cmp"]
    print(f"{r['n_spheres']} spheres in {N_COLUMNS} columns: {time.perf_counter() - t0:.0f} s wall clock, "
          f"{time.process_time() - c0:.0f} s CPU")
    ps = r["profiles"]
    sliding = sum(p.sliding_count.sum() for p in ps) / sum(p.contact_count.sum() for p in ps)
    by_bin = sum(p.shear_up_force_sum_n for p in ps) / sum(p.normal_force_sum_n for p in ps)
    print(f"mobilised wall friction {r['wall_friction']:.3f} (contact coefficient {WALL_FRICTION}; by depth bin "
          f"{np.round(by_bin, 3)}; {sliding:.0%} of wall contacts at the Coulomb limit); solid fractions "
          f"{[round(g.solid_fraction, 4) for g in r['geometry']]}")
    print(f"K = {c.lateral_ratio:.3f}; floor {c.measured_base_load_n:.3f} N, Janssen {c.janssen_base_load_n:.3f} N "
          f"({c.base_rel_error:+.1%}); weight {c.weight_n:.3f} N; floor + wall friction "
          f"{r['floor_n'] + r['tubes_up_n']:.3f} N")
    for z, m, j, hy in zip(c.bin_mid_depth_m, c.measured_stress_pa, c.janssen_stress_pa, c.hydrostatic_stress_pa):
        print(f"  depth {z:.3f} m: wall stress {m:7.1f} Pa, Janssen {j:7.1f} Pa ({m / j - 1:+.1%}), "
              f"hydrostatic {hy:7.1f} Pa")
    print("failures:", jc.acceptance_failures(c, K_RANGE) or "none")
