"""The analytic stand-in must show the thesis's trends, or the calibration loop tested on it proves nothing."""
import numpy as np
import pytest

from engine.lab import Cancelled
from engine.lab.spec import JobSpec
from calibration.evaluator_registry import run_job


def _run(seed=0, fidelity="thesis", **params):
    return run_job("analytic", JobSpec(seed=seed, fidelity=fidelity, parameters=params))


def test_bulk_density_slope_matches_table_4_6():
    # Table 4.6: bulk density vs particle density, fitted slope ~0.56 (560.6 ... 5617.1 over 1000 ... 10000).
    table_rho_p = np.array([1000, 4000, 7000, 10000.0])
    table_rho_b = np.array([560.6, 2232.1, 3926.9, 5617.1])
    thesis_slope = np.polyfit(table_rho_p, table_rho_b, 1)[0]
    ours = [_run(seed=1, particle_density_kg_m3=r, friction_pp=0.1).value("fill", "bulk_density_kg_m3")
            for r in table_rho_p]
    assert np.polyfit(table_rho_p, ours, 1)[0] == pytest.approx(thesis_slope, rel=0.10)


def test_frictionless_packing_is_denser_and_phi_rises_with_friction():
    dens = [_run(friction_pp=mu).value("fill", "bulk_density_kg_m3") for mu in (0.0, 0.5)]
    assert dens[0] > dens[1]  # Table 4.8
    phis = [_run(friction_pp=mu).value("dst", "friction_angle_deg") for mu in (0.0, 0.1, 0.5, 1.0)]
    assert np.all(np.diff(phis) > 0)


def test_same_seed_same_result_and_replicates_scatter():
    assert _run(seed=3).model_dump()["properties"] == _run(seed=3).model_dump()["properties"]
    assert _run(seed=3).value("cct", "confined_modulus_pa") != _run(seed=4).value("cct", "confined_modulus_pa")


def test_round_particles_cannot_reach_measured_friction_angle_without_rolling_resistance():
    # The thesis aggregate: phi = 60.6 deg (DST, Table 4.10); spheres without rolling resistance saturate well below.
    best = _run(friction_pp=5.0).value("dst", "friction_angle_deg")
    with_rr = run_job("analytic", JobSpec(fidelity="thesis", parameters={
        "friction_pp": 0.86, "effects": {"rolling_epsd2": {"rolling_friction": 0.3}}}))
    assert best < 50.0 < with_rr.value("dst", "friction_angle_deg")


def test_cancellation_is_honoured(monkeypatch):
    monkeypatch.setenv("DEMCAL_ANALYTIC_DURATION_S", "5")
    with pytest.raises(Cancelled):
        run_job("analytic", JobSpec(), should_cancel=lambda: True)


def test_unknown_evaluator_is_refused():
    with pytest.raises(ValueError, match="unknown evaluator"):
        run_job("magic", JobSpec())
