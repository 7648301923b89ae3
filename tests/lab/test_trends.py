"""The thesis's trends reproduced at screening fidelity (issue 3, 'What it must show').

Every expected number comes from the thesis's tables or from physics; none from our own runs.
"""
import math

import pytest

from engine.lab import run_job
from engine.lab.registry import units
from engine.lab.spec import JobSpec
from lab_runs import AOR_FRICTIONS, AOR_STAGES, aor_pile

pytestmark = pytest.mark.slow


def test_example_battery_runs_as_is(example_battery):
    r = example_battery
    got = {(p.test, p.quantity) for p in r.properties}
    # the unload-reload modulus is reported only where options.cct_unload_reload_stresses_pa asks for it
    on_request = {("cct", "unload_reload_modulus_pa")}
    for test in ("fill", "cct", "dst"):
        for quantity in units()[test]:
            if (test, quantity) not in on_request:
                assert (test, quantity) in got, (test, quantity)
    assert not on_request & got
    area = math.pi * 0.2**2
    for force in (1885.0, 3495.0, 5105.0, 6760.0):  # Table A.7 loads, as stresses
        tau = r.value("dst", "residual_shear_stress_pa", normal_stress_pa=force / area)
        assert 0 < tau < 3 * force / area
    # Eq. 4.4 / 4.7 hold between the reported values
    rho_b = r.value("fill", "bulk_density_kg_m3")
    e = r.value("fill", "voids_ratio")
    assert e == pytest.approx(2500.0 / rho_b - 1)
    assert r.value("fill", "porosity") == pytest.approx(e / (e + 1))
    # Eq. 4.12
    h = r.value("fill", "packing_height_m")
    assert r.value("cct", "bulk_stiffness_n_per_m") == pytest.approx(area / h * r.value("cct", "confined_modulus_pa"))
    prov = r.provenance
    assert prov.steps > 0 and prov.simulated_time_s > 0 and prov.wall_time_s > 0
    # quasi-static: the default speed factor keeps the inertial number well under the 1e-2 limit
    assert prov.max_inertial_number is not None and prov.max_inertial_number < 1e-2
    assert not [w for w in prov.warnings if "inertial" in w]
    for key in ("cct", "dst_envelope", "fill_settling"):
        assert key in r.curves


def test_bulk_density_linear_in_particle_density(soft_light, soft_heavy):
    # Table 4.6: slope 0.56 kg/m3 per kg/m3 (560.6 -> 5,617.1 over 1,000 -> 10,000), within 10 %
    slope = (soft_heavy[0]["bulk_density_kg_m3"] - soft_light[0]["bulk_density_kg_m3"]) / 7500.0
    assert slope == pytest.approx(0.56, rel=0.10)
    # linear through the origin as in Table 4.6 (intercept -1.3 kg/m3): the solid fraction barely moves
    assert soft_heavy[0]["porosity"] == pytest.approx(soft_light[0]["porosity"], abs=0.02)


def test_frictionless_packing_is_denser(frictionless_battery, soft_light):
    # Table 4.8: 1,461.2 kg/m3 at mu_pp = 0 against 1,397.1 at 0.1 (same rho_p = 2,500)
    assert frictionless_battery.value("fill", "porosity") < soft_light[0]["porosity"]
    assert frictionless_battery.value("fill", "bulk_density_kg_m3") > soft_light[0]["bulk_density_kg_m3"]


def test_confined_modulus_rises_with_particle_stiffness(soft_light, stiff_light):
    # Table 4.7: E' 5.62 -> 11.55 MPa for k_p 1.0 -> 2.3 MN/m; linear contacts give E' ~ k_p
    e_soft, e_stiff = soft_light[1].confined_modulus_pa, stiff_light[1].confined_modulus_pa
    assert e_stiff > 1.5 * e_soft


def test_friction_angle_rises_with_interparticle_friction(frictionless_battery, mid_friction_dst, example_battery):
    # Table 4.8: phi 9.9, 35.0, 61.2 deg at mu_pp 0, 0.5, 0.86 (monotonic)
    phis = [r.value("dst", "friction_angle_deg") for r in (frictionless_battery, mid_friction_dst, example_battery)]
    assert phis[0] < phis[1] < phis[2]


def test_mohr_coulomb_fit_of_a_well_behaved_run(low_friction_dst):
    # the thesis's own envelopes are straight lines through four loads (Eqs. 3.1-3.2, Table 4.10)
    assert low_friction_dst.value("dst", "mohr_coulomb_r2") > 0.95


# The angle-of-repose trend's piles (lab_runs.AOR_STAGES at each of lab_runs.AOR_FRICTIONS). One screening
# pile is ~120 pyramid clumps, 2-4 clumps high, and its angle is chaotic in the trajectory: moving every
# inserted body by one ulp (a round-off change, as a new summation order in the engine is) moved seed 3's
# angle at mu_pp 0.1 from 19.0 to 13.7 deg and at 0.86 from 29.1 to 21.4 deg. So one pile is one draw: over
# 8-9 such draws per friction (docs/lab.md) the pile angle has a standard deviation of 5.0 deg at 0.1 and
# 6.0 deg at 0.86 about a mean rise of 10.3 deg, and one seed alone fell short of a 5 deg rise about one
# time in four. A pile costs 1-2 min of a core, so the test is group-sequential (two stages of three piles
# per friction). Stage 1 passes when its rise exceeds STAGE_1_BAR; otherwise stage 2's piles run and the
# mean of all six per friction must rise by more than FINAL_BAR. From those spreads (rise standard error
# 4.5 deg after stage 1, 3.2 deg after both; stage 1's rise and the final one correlate 1/sqrt(2); a
# bivariate normal): the model as measured fails about one time in 22 (0.045; the fixed six-pile test:
# 0.048), a model without the trend (rise 0) passes about one time in 14 (0.069; fixed: 0.058), and the
# expected cost is 8.3 piles per run instead of 12 (stage 1 alone passes 61 % of the time).
STAGE_1_BAR = 9.0
FINAL_BAR = 5.0


def _rise(piles: dict) -> tuple[float, list, list]:
    low = [piles[AOR_FRICTIONS[0], seed] for seed in sorted({s for _, s in piles})]
    high = [piles[AOR_FRICTIONS[1], seed] for seed in sorted({s for _, s in piles})]
    return sum(high) / len(high) - sum(low) / len(low), low, high


def test_angle_of_repose_rises_with_friction(aor_piles, lab_run):
    # Table 5.3: 12 deg at mu_pp 0.1, 38 deg at 0.86, a rise of 26 deg. Asked: a rise of the mean
    # angle over the piles of at least 5 deg, 1.5 x the spread of the thesis's own readings of one pile
    # (Table 5.2: 43, 36, 38, 36 deg, standard deviation 3.3 deg).
    assert AOR_FRICTIONS == (0.1, 0.86)
    runs = dict(zip([(mu, seed) for mu in AOR_FRICTIONS for seed in AOR_STAGES[0]], aor_piles))
    rise, low, high = _rise({k: r.value("aor", "angle_of_repose_deg") for k, r in runs.items()})
    if rise <= STAGE_1_BAR:
        later = [(mu, seed) for mu in AOR_FRICTIONS for seed in AOR_STAGES[1]]
        runs.update(zip(later, lab_run([aor_pile(mu, seed) for mu, seed in later])))
        rise, low, high = _rise({k: r.value("aor", "angle_of_repose_deg") for k, r in runs.items()})
        assert rise > FINAL_BAR, (rise, low, high)
    for r in runs.values():
        assert len([p for p in r.properties if "sector" in p.condition]) >= 6
        assert not [w for w in r.provenance.warnings if "aor" in w], r.provenance.warnings


def test_anchor_peak_exceeds_the_weight_it_lifts(anchor_pull):
    # statics: before the packing fails, the plate carries at least the column of grains above it
    # (plate area less the tube's, times rho_b g L); Table 5.5 (A) measured 175.6 N for L = 170 mm
    peak = anchor_pull.value("anchor", "peak_pull_force_n", packing_height_m=0.17, pull_speed_m_s=0.027)
    column_weight = 1200.0 * 9.81 * 0.17 * (0.110**2 - 0.050**2)  # rho_b of a loose sphere packing
    assert peak > column_weight
    curve = anchor_pull.curves["anchor"]
    assert max(curve["displacement_m"]) >= 0.03


def test_same_seed_same_result():
    # a tiny packing (50 mm spheres, ~60 bodies): the whole fill twice, bit for bit
    spec = JobSpec(test="fill", seed=7, parameters={"particle_radius_m": 0.05})
    a, b = run_job(spec), run_job(spec)
    assert [p.value for p in a.properties] == [p.value for p in b.properties]
    assert a.provenance.steps == b.provenance.steps


def test_preparation_friction_sets_the_packing_and_the_tests_see_the_calibrated_friction(
        frictionless_battery, rained_frictionless_fill):
    # a packing rained at mu_pp = 0 is the frictionless packing, whatever friction the tests use next
    fill_properties, friction_after_fill = rained_frictionless_fill
    frictionless = frictionless_battery.value("fill", "bulk_density_kg_m3")
    assert fill_properties["bulk_density_kg_m3"] == pytest.approx(frictionless, rel=1e-9)
    assert friction_after_fill == 0.86
