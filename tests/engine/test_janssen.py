"""A settled column in a cylinder: wall normal stress against depth follows Janssen's law.

Janssen: sigma_h(z) = A (1 - exp(-z / l)) with A = rho_b g D / (4 mu) and l = D / (4 mu K), mu the
mobilised wall friction (at most the wall's coefficient) and K the lateral stress ratio. We fit A and l
to the wall stress profile, require every depth bin within 15 % of the fit, and the fitted mu and K to be
physical (mu <= wall friction, 0.2 < K < 1.5); a hydrostatic profile (no saturation) would fail.
"""
import math

import numpy as np
import pytest
from scipy.optimize import curve_fit

from engine.config import CylinderGeom, PlaneGeom, WallSpec
from engine.simulation import Simulation

from engine_helpers import G, config

RC = 0.03
R = 0.003
MU_W = 0.8
RHO = 2500.0


@pytest.mark.slow
def test_wall_stress_follows_janssen():
    cfg = config(mat_normal_stiffness_n_per_m=5e4, mat_density_kg_m3=RHO, mat_friction=0.5,
                 mat_damping_ratio_normal=0.8, mat_damping_ratio_shear=0.0, mat_local_damping=0.2)
    sim = Simulation(cfg)
    rng = np.random.default_rng(11)
    step = 2.2 * R
    g = np.arange(-RC + step, RC - step / 2, step)
    xy = np.array([(x, y) for x in g for y in g if math.hypot(x, y) < RC - 1.2 * R])
    n = 1800
    layers = int(math.ceil(n / len(xy)))
    pos = np.array([(x, y, step * (k + 0.6)) for k in range(layers) for x, y in xy])[:n]
    pos[:, :2] += rng.uniform(-0.05 * R, 0.05 * R, (n, 2))
    radii = rng.uniform(0.85 * R, 1.15 * R, n)
    sim.add_spheres(pos, radii)
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), normal_stiffness_n_per_m=5e5, friction=0.5))
    sim.add_wall(WallSpec(name="tube", geometry=CylinderGeom(base_m=(0, 0, -0.01), radius_m=RC,
                                                               height_m=1.0), normal_stiffness_n_per_m=5e5,
                          friction=MU_W))
    sim.run(duration_s=0.8)
    assert sim.kinetic_energy() < 1e-4 * sim.body_masses_kg().sum() * G * 0.01  # at rest

    top = np.sort(sim.sphere_positions_m()[:, 2] + radii)[-40:].mean()
    loads = sim.wall_contact_loads("tube")
    p, f = loads["points_m"], loads["forces_n"]
    radial = (f[:, 0] * p[:, 0] + f[:, 1] * p[:, 1]) / np.hypot(p[:, 0], p[:, 1])
    depth = top - p[:, 2]
    width = 2 * RC / 2
    edges = np.arange(width, top - 2 * R - width, width)  # skip the loose surface and the floor corner
    z_mid, stress = [], []
    for a, b in zip(edges[:-1], edges[1:]):
        sel = (depth >= a) & (depth < b)
        z_mid.append(0.5 * (a + b))
        stress.append(radial[sel].sum() / (2 * math.pi * RC * (b - a)))
    z_mid, stress = np.array(z_mid), np.array(stress)
    assert len(z_mid) >= 5

    janssen = lambda z, a, l: a * (1.0 - np.exp(-z / l))
    (a_fit, l_fit), _ = curve_fit(janssen, z_mid, stress, p0=(stress.max(), 2 * RC))
    assert np.max(np.abs(stress - janssen(z_mid, a_fit, l_fit)) / janssen(z_mid, a_fit, l_fit)) < 0.15

    mass = sim.body_masses_kg().sum()
    rho_b = mass / (math.pi * RC ** 2 * top)
    mu_eff = rho_b * G * 2 * RC / (4 * a_fit)
    k_ratio = 2 * RC / (4 * mu_eff * l_fit)
    assert mu_eff <= MU_W * 1.05
    assert 0.2 < k_ratio < 1.5
    # saturation: the deepest stress is well below the hydrostatic K rho_b g z
    assert stress[-1] < 0.8 * k_ratio * rho_b * G * z_mid[-1]
