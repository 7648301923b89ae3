"""End-to-end campaign on the DEM engine at screening fidelity (slow): 2^2 design + 2 centre runs + confirmation.

Kept small so that it fits the CI budget: the runs are fills alone (no CCT/DST), which is what a
bulk-density calibration needs (thesis section 4.5.4 calibrated particle density on the fill).
"""
from __future__ import annotations

import math

import pytest

from conftest_s2 import API, run_to_end, s2, thesis_material_id  # noqa: F401

pytestmark = pytest.mark.slow


def test_dem_campaign_at_screening_fidelity(s2):
    client, app, settings = s2
    body = {
        "name": "dem screening", "material_id": thesis_material_id(client), "evaluator": "dem",
        "fidelity": "screening", "test": "fill",
        "factors": [{"name": "particle_density_kg_m3", "low": 2300.0, "high": 2700.0},
                    {"name": "friction_pp", "low": 0.3, "high": 0.9}],
        "design": {"type": "full", "centre_runs": 2},
        "targets": [{"test": "fill", "quantity": "bulk_density_kg_m3"}],
        "seed": 3,
    }
    created = client.post(f"{API}/campaigns", json=body)
    assert created.status_code == 201, created.text
    cid = created.json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    final = run_to_end(client, app, settings, cid)
    assert final["status"] == "completed", final["error"]

    (iteration,) = client.get(f"{API}/campaigns/{cid}/iterations").json()
    assert len(iteration["runs"]) == 7  # 4 corners + 2 centre replicates + confirmation
    model = client.get(f"{API}/campaigns/{cid}/models").json()["models"]["fill__bulk_density_kg_m3"]
    assert model["ok"], model.get("error")
    # rho_b = rho_p (1 - n): with friction fixed, d rho_b / d rho_p is the solid fraction of a random
    # packing of spheres, between random loose (~0.55) and random close (~0.64) packing less wall effects.
    coefficients = {c["name"]: c["estimate"] for c in model["fit"]["coefficients_natural"]}
    slope = coefficients["particle_density_kg_m3"] + coefficients.get("particle_density_kg_m3*friction_pp", 0.0) * 0.6
    assert 0.45 < slope < 0.66
    # centre replicates with different seeds pack differently: the simulator's noise floor is measured
    assert model["pure_error_sd"] is not None and model["pure_error_sd"] > 0

    report = client.get(f"{API}/campaigns/{cid}/report").json()
    (row,) = report["targets"]
    assert row["status"] == "modelled" and row["measured"] == pytest.approx(1397.8)
    assert math.isfinite(row["confirmed"]) and math.isfinite(row["standardised_residual"])
    optimum = report["optimum"]
    assert 2300.0 <= optimum["particle_density_kg_m3"] <= 2700.0 and 0.3 <= optimum["friction_pp"] <= 0.9
