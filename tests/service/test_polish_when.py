"""``polish_when="surrogate_misses"``: polish only the iterations whose response surfaces missed the
confirmation batteries, as the library loop does (calibration/loop.py polishes when ``adequacy`` fails).

Both cases are physical, on the analytic evaluator: the thesis's three factors over the thesis's box,
where a two-level surface of each target holds (every confirmation inside its prediction interval), and
the same with rolling resistance as a fourth factor from 0 to 0.5 (mu_pp from 0.05), where the
stand-in's friction angle saturates in mu_r and mu_pp together, as a DEM packing's does (Estrada et al.
2008), and a two-level surface cannot follow it: the surrogate's optimum is not the simulator's, which
is what polishing on the batteries corrects.
"""
from __future__ import annotations

from conftest_s2 import API, campaign_body, run_to_end, s2, thesis_material_id  # noqa: F401

ROLLING = {"name": "effects.rolling_epsd2.rolling_friction", "low": 0.0, "high": 0.5}


def _campaign(client, app, settings, **overrides) -> tuple[dict, list[dict]]:
    body = campaign_body(thesis_material_id(client), polish_when="surrogate_misses", diagnose=False, **overrides)
    response = client.post(f"{API}/campaigns", json=body)
    assert response.status_code == 201, response.text
    cid = response.json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    (iteration,) = client.get(f"{API}/campaigns/{cid}/iterations").json()["items"]
    return client.get(f"{API}/campaigns/{cid}/report").json(), iteration["runs"]


def test_surfaces_that_predict_the_confirmation_are_not_polished(s2):
    client, app, settings = s2
    report, runs = _campaign(client, app, settings)
    # no polishing: the report's check is on the confirmation batteries themselves, and it holds
    assert not [r for r in runs if r["kind"] == "polish"]
    assert report["surrogate_check"]["confirmed"] is True
    assert report["polish"]["steps"] == 0 and report["polish"]["skipped"] == report["surrogate_check"]["reason"]


def test_surfaces_that_miss_the_confirmation_are_polished(s2):
    client, app, settings = s2
    factors = campaign_body(0)["factors"]
    factors[2] = {"name": "friction_pp", "low": 0.05, "high": 1.0}
    report, runs = _campaign(client, app, settings, factors=[*factors, ROLLING])
    polish_runs = [r for r in runs if r["kind"] == "polish"]
    seeds = {r["seed"] for r in runs if r["kind"] == "confirmation"}
    # at least one trial point at every confirmation seed (the Jacobian is the surfaces' slopes: no
    # round of forward differences), and a whole number of points
    assert polish_runs and len(polish_runs) % len(seeds) == 0
    assert "skipped" not in report["polish"] and report["polish"]["batteries"] == len(polish_runs)


def test_a_jacobian_on_the_batteries_costs_one_point_per_factor_and_seed(s2):
    client, app, settings = s2
    factors = campaign_body(0)["factors"]
    factors[2] = {"name": "friction_pp", "low": 0.05, "high": 1.0}
    report, runs = _campaign(client, app, settings, factors=[*factors, ROLLING], polish_jacobian="batteries")
    seeds = {r["seed"] for r in runs if r["kind"] == "confirmation"}
    first_round = [r for r in runs if r["kind"] == "polish" and r["std_order"] < 1000]
    assert len(first_round) == 4 * len(seeds)  # round 0: one point per factor at every seed


def test_polish_when_is_validated(s2):
    client, _, _ = s2
    material_id = thesis_material_id(client)
    response = client.post(f"{API}/campaigns", json=campaign_body(material_id, polish_when="sometimes"))
    assert response.status_code == 422, response.text
    assert response.json()["detail"][0]["loc"] == ["body", "polish_when"], response.text
    # the default decides on polishing a campaign that asks for none: nothing to decide, accepted as such
    response = client.post(f"{API}/campaigns", json=campaign_body(material_id, polish_steps=0))
    assert response.status_code == 201 and response.json()["config"]["polish_when"] == "surrogate_misses", response.text
