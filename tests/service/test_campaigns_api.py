"""Campaign endpoints: creation validation, legal and illegal state changes, products before they exist."""
from __future__ import annotations

import pytest

from conftest_s2 import API, campaign_body, drain, error_loc, s2, thesis_material_id  # noqa: F401
from service.campaigns.runner import CampaignRunner

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)

PRODUCTS = ("design", "models", "optimum", "confirmation", "report")


def test_create_and_read(s2):
    client, _, _ = s2
    material_id = thesis_material_id(client)
    response = client.post(f"{API}/campaigns", json=campaign_body(material_id), headers={"X-Client-Id": "lab-a"})
    assert response.status_code == 201, response.text
    campaign = response.json()
    assert campaign["status"] == "draft" and campaign["current_iteration"] == 0 and campaign["phase"] is None
    assert client.get(f"{API}/campaigns/{campaign['id']}").json()["name"] == "thesis calibration"
    assert [c["id"] for c in client.get(f"{API}/campaigns", params={"status": "draft"}).json()["items"]] == [campaign["id"]]
    assert client.get(f"{API}/campaigns", params={"status": "running"}).json()["items"] == []
    assert client.get(f"{API}/campaigns", params={"status": "sleeping"}).status_code == 422
    assert client.get(f"{API}/campaigns/{campaign['id']}/iterations").json()["items"] == []


@pytest.mark.parametrize("change, loc", [
    ({"factors": [{"name": "grain_size", "low": 1, "high": 2}]}, ["body", "factors"]),
    ({"factors": [{"name": "friction_pp", "low": 0.9, "high": 0.3}]}, ["body", "factors", 0]),
    ({"factors": [{"name": "friction_pp", "low": -0.5, "high": 0.3}]}, ["body"]),
    ({"fixed_parameters": {"friction_pp": 0.5}}, ["body", "fixed_parameters"]),
    ({"fixed_parameters": {"friction_pw": -1.0}}, ["body", "fixed_parameters"]),
    ({"options": {"cct_cycles": 0}}, ["body", "options"]),
    ({"evaluator": "quantum"}, ["body", "evaluator"]),
    ({"fidelity": "ultra"}, ["body", "fidelity"]),
    ({"design": {"type": "fractional"}}, ["body", "design"]),
    ({"design": {"type": "full", "centre_runs": -2}}, ["body", "design", "centre_runs"]),
    ({"targets": [{"test": "dst", "quantity": "porosity"}]}, ["body", "targets", 0, "quantity"]),
    ({"constraints": ["friction_pw <= friction_pp"]}, ["body", "constraints", 0]),
    ({"constraints": ["friction_pp <= import os"]}, ["body", "constraints", 0]),
    ({"priors": [{"parameter": "friction_pw", "value": 0.6, "uncertainty": 0.05}]}, ["body", "priors", 0]),
    # cross-field rules point at the field they refuse (service.errors._field_of_model_error)
    ({"automatic": True, "diagnose": False}, ["body", "automatic"]),
    ({"diagnose_always": True, "diagnose": False}, ["body", "diagnose_always"]),
    ({"name": ""}, ["body", "name"]),
    ({"model_discrepancy": [{"test": "shear", "relative_sd": 0.1}]}, ["body", "model_discrepancy", 0]),
    ({"model_discrepancy": [{"test": "cct", "relative_sd": 2.0}]}, ["body", "model_discrepancy", 0, "relative_sd"]),
])
def test_create_rejects_bad_input_naming_the_field(s2, change, loc):
    client, _, _ = s2
    response = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), **change))
    assert response.status_code == 422, response.text
    assert error_loc(response)[:len(loc)] == loc


def test_create_for_missing_material_is_404(s2):
    client, _, _ = s2
    response = client.post(f"{API}/campaigns", json=campaign_body(999))
    assert response.status_code == 404 and error_loc(response) == ["body", "material_id"]


def test_state_machine_and_conflicts(s2):
    client, app, settings = s2
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
    for action in ("pause", "resume"):
        response = client.post(f"{API}/campaigns/{cid}/{action}")
        assert response.status_code == 409 and error_loc(response) == ["path", "campaign_id"]
    for product in PRODUCTS:  # nothing exists before the first iteration
        assert client.get(f"{API}/campaigns/{cid}/{product}").status_code == 404
    assert client.post(f"{API}/campaigns/{cid}/start").json()["status"] == "running"
    assert client.post(f"{API}/campaigns/{cid}/start").status_code == 409
    assert client.post(f"{API}/campaigns/{cid}/resume").status_code == 409

    CampaignRunner(app.state.session_factory, settings).tick()  # design made, batteries queued
    status = client.get(f"{API}/campaigns/{cid}").json()
    assert status["phase"] == "batteries" and status["runs_total"] == 11
    assert client.get(f"{API}/campaigns/{cid}/design").json()["n_runs"] == 11
    for product in ("models", "optimum", "confirmation", "report"):  # exist later: 409, not 404
        response = client.get(f"{API}/campaigns/{cid}/{product}")
        assert response.status_code == 409, product

    assert client.post(f"{API}/campaigns/{cid}/pause").json()["status"] == "paused"
    assert client.post(f"{API}/campaigns/{cid}/pause").status_code == 409
    drain(app, settings)  # queued batteries still run while paused ...
    CampaignRunner(app.state.session_factory, settings).tick()
    assert client.get(f"{API}/campaigns/{cid}").json()["phase"] == "batteries"  # ... but the campaign waits
    assert client.post(f"{API}/campaigns/{cid}/resume").json()["status"] == "running"
    CampaignRunner(app.state.session_factory, settings).tick()
    assert client.get(f"{API}/campaigns/{cid}").json()["phase"] == "confirmation"
    assert client.get(f"{API}/campaigns/{cid}/models").status_code == 200
    assert client.get(f"{API}/campaigns/{cid}/optimum").status_code == 200
    assert client.get(f"{API}/campaigns/{cid}/confirmation").json()["status"] == "queued"
    assert client.get(f"{API}/campaigns/{cid}/report").status_code == 409


def test_unknown_campaign_is_404_everywhere(s2):
    client, _, _ = s2
    for method, path in [("get", ""), ("post", "/start"), ("post", "/pause"), ("post", "/resume"),
                         ("get", "/iterations"), ("get", "/iterations/1"), *[("get", f"/{p}") for p in PRODUCTS]]:
        response = getattr(client, method)(f"{API}/campaigns/4242{path}")
        assert response.status_code == 404, path
        assert error_loc(response) == ["path", "campaign_id"], path
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
    response = client.get(f"{API}/campaigns/{cid}/iterations/3")
    assert response.status_code == 404 and error_loc(response) == ["path", "number"]
    assert client.get(f"{API}/campaigns/{cid}/report", params={"number": 0}).status_code == 422


def test_generators_doe_refuses_are_422_at_creation(s2):
    client, _, _ = s2
    body = campaign_body(thesis_material_id(client), design={"type": "fractional", "generators": ["C=AX"]})
    response = client.post(f"{API}/campaigns", json=body)
    assert response.status_code == 422 and error_loc(response) == ["body", "design", "generators"]


def test_batteries_are_queued_in_randomised_run_order(s2):
    from service.models.campaign import CampaignRun

    client, app, settings = s2
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    CampaignRunner(app.state.session_factory, settings).tick()
    with app.state.session_factory() as session:
        runs = session.query(CampaignRun).order_by(CampaignRun.job_id).all()
    assert [r.run_order for r in runs] == list(range(1, 12))
    assert [r.std_order for r in runs] != list(range(1, 12))  # randomised (seeded) order differs from std order
