"""Campaigns and jobs at a resolution through the API (issue 29 item 3), on the analytic stand-in: a campaign at
a material resolution runs in its material's rig with its particles; the old fidelity names keep their presets,
and what the preset's rig cannot be compared with is left out, named, never compared silently."""
from __future__ import annotations

import math

import pytest
from conftest_s2 import API, campaign_body, run_to_end, running_app, s2, s2_settings, thesis_material_id  # noqa: F401

THESIS_RIG = "thesis-590mm-shear-box"
# the bulk mass without the bulk density: with it, struck off at the level, the mass is rho_b A H, the same
# weighing, and is counted once through the density (calibration.comparable.once_each)
MEASURED_IN_THE_BOX = [{"test": "fill", "quantity": "bulk_mass_kg"},
                       {"test": "dst", "quantity": "friction_angle_deg"},
                       {"test": "dst", "quantity": "dilatancy_angle_deg"}]


def _loc(response) -> list:
    return response.json()["detail"][0]["loc"]


def test_a_coarse_campaign_runs_in_its_materials_rig_and_compares_its_bulk_mass(s2, tmp_path):
    """The thesis aggregate coarse-grained in its own 590 mm box: the campaign copies the material's rig and
    particles, every job carries them, and the bulk mass is a target, each battery's the bulk density times that
    box's packing struck off at its level, pi (0.295 m)^2 x 0.330 m (nothing left out)."""
    client, app, settings = s2
    body = campaign_body(thesis_material_id(client), targets=MEASURED_IN_THE_BOX,
                         resolution={"mode": "coarse", "scale_factor": 1.3}, design={"type": "full", "centre_runs": 2})
    created = client.post(f"{API}/campaigns", json=body)
    assert created.status_code == 201, created.text
    campaign = created.json()
    assert campaign["fidelity"] == "coarse" and campaign["config"]["rig"]["name"] == THESIS_RIG
    assert campaign["config"]["particles"]["shapes"][0]["shape"] == "pyramid"
    assert not any("left out" in w for w in campaign["warnings"])
    assert not any("container_diameter_m" in w for w in campaign["warnings"])  # x 1.3: within the standards
    client.post(f"{API}/campaigns/{campaign['id']}/start")
    assert run_to_end(client, app, settings, campaign["id"])["status"] == "completed"
    report = client.get(f"{API}/campaigns/{campaign['id']}/report").json()
    assert report["left_out_targets"] == []
    rows = {r["quantity"]: r for r in report["targets"]}
    assert rows["bulk_mass_kg"]["status"] == "modelled"
    job = client.get(f"{API}/jobs", params={"campaign_id": campaign["id"], "limit": 1}).json()["items"][0]
    spec = client.get(f"{API}/jobs/{job['id']}").json()["spec"]
    result = client.get(f"{API}/jobs/{job['id']}/result?include_curves=false").json()
    values = {p["quantity"]: p["value"] for p in result["properties"]
              if p["test"] == "fill" and not p.get("condition")}
    assert values["bulk_mass_kg"] / values["bulk_density_kg_m3"] == pytest.approx(math.pi * 0.295 ** 2 * 0.330,
                                                                                  rel=1e-9)
    assert spec["resolution"]["scale_factor"] == 1.3 and spec["rig"]["name"] == THESIS_RIG
    # the material card states this set-up: the 590 mm rig's record, the material's own particles and the
    # shapes at x 1.3 (Table 4.2's pyramids of 7.5-10.5 mm spheres simulated at 9.75-13.65 mm)
    response = client.get(f"{API}/campaigns/{campaign['id']}/material-card")
    assert response.status_code == 200, response.text
    card = response.json()
    rig = card["rig"]
    assert (rig["fidelity"], rig["resolution"], rig["scale_factor"]) == (None, "coarse", 1.3)
    assert rig["rig_record"]["name"] == THESIS_RIG and rig["container_radius_m"] == pytest.approx(0.295)
    assert rig["material_particles"]["shapes"][0]["size"]["radius_min_m"] == 0.0075
    pyramid = next(s for s in card["particles"]["shapes"] if s["shape"] == "pyramid")["radius_distribution"]
    assert (pyramid["radius_min_m"], pyramid["radius_max_m"]) == pytest.approx((0.0075 * 1.3, 0.0105 * 1.3))
    # imported back (another installation) and exported again: the same card; and a LIGGGHTS include of it
    with running_app(s2_settings(tmp_path).model_copy(update={"seed_materials": False})) as (other, _):
        imported = other.post(f"{API}/materials/import-card", json=card)
        assert imported.status_code == 201, imported.text
        assert other.get(f"{API}/materials/{imported.json()['id']}/material-card").json() == card
    include = client.get(f"{API}/campaigns/{campaign['id']}/export", params={"format": "liggghts"})
    assert include.status_code == 200 and "multisphere" in include.text


def test_the_old_screening_preset_leaves_the_other_boxs_bulk_mass_out_naming_it(s2):
    """fidelity "screening" (stored campaigns, old clients) still runs the 400 mm box; its bulk mass is of
    another container than the 590 mm box's measurement, so it is left out with the reason, not compared."""
    client, app, settings = s2
    body = campaign_body(thesis_material_id(client), fidelity="screening", targets=MEASURED_IN_THE_BOX,
                         design={"type": "full", "centre_runs": 2})
    campaign = client.post(f"{API}/campaigns", json=body).json()
    assert campaign["fidelity"] == "screening" and campaign["config"]["rig"] is None
    assert any(w.startswith("fill/bulk_mass_kg left out of the targets") and "appendix-a-400mm-shear-box" in w
               for w in campaign["warnings"])
    client.post(f"{API}/campaigns/{campaign['id']}/start")
    assert run_to_end(client, app, settings, campaign["id"])["status"] == "completed"
    report = client.get(f"{API}/campaigns/{campaign['id']}/report").json()
    assert [(t["test"], t["quantity"]) for t in report["left_out_targets"]] == [("fill", "bulk_mass_kg")]
    assert "bulk_mass_kg" not in {r["quantity"] for r in report["targets"]}


def test_bad_resolutions_are_422s_naming_the_field(s2):
    client, _, _ = s2
    material_id = thesis_material_id(client)
    for resolution in ("fine", {"mode": "coarse", "scale_factor": 0.5}, {"mode": "coarse", "speed": 2}):
        refused = client.post(f"{API}/campaigns", json=campaign_body(material_id, resolution=resolution))
        assert refused.status_code == 422 and _loc(refused)[:2] == ["body", "resolution"], refused.text
        refused = client.post(f"{API}/jobs", json={"evaluator": "analytic", "resolution": resolution})
        assert refused.status_code == 422 and _loc(refused)[:2] == ["body", "resolution"], refused.text
        # one branch judged: a bad object is not also told the names, nor a bad name the object's fields
        details = refused.json()["detail"]
        branch = "name" if isinstance(resolution, str) else "object"
        assert {tuple(d["loc"][:3]) for d in details} == {("body", "resolution", branch)}, refused.text
    # a job at a material resolution needs its rig and particles
    refused = client.post(f"{API}/jobs", json={"evaluator": "analytic", "resolution": "coarse"})
    assert refused.status_code == 422 and _loc(refused) == ["body", "rig"], refused.text
    # a material without a rig cannot run "in the rig it was measured in"
    bare = client.post(f"{API}/materials", json={"name": "no rig", "measurements": [
        {"test": "fill", "quantity": "bulk_density_kg_m3", "values": [1400.0, 1390.0]}]}).json()
    refused = client.post(f"{API}/campaigns", json=campaign_body(bare["id"], resolution="as_measured", targets=None))
    assert refused.status_code == 422 and _loc(refused) == ["body", "resolution"] and "no rig" in refused.text
    assert client.get(f"{API}/campaigns").json()["items"] == []
    # a schedule's template is checked the same way (its firings take the material's rig when they fire)
    refused = client.post(f"{API}/schedules", json={"name": "nightly", "cron": "@daily", "template": campaign_body(
        bare["id"], resolution="as_measured", targets=None)})
    assert refused.status_code == 422 and _loc(refused) == ["body", "template", "resolution"], refused.text
    accepted = client.post(f"{API}/schedules", json={"name": "nightly", "cron": "@daily", "template": campaign_body(
        material_id, resolution={"mode": "coarse", "scale_factor": 1.3})})
    assert accepted.status_code == 201, accepted.text


def test_a_job_alias_round_trips_and_keeps_its_preset(s2):
    client, app, settings = s2
    job = client.post(f"{API}/jobs", json={"evaluator": "analytic", "test": "fill", "resolution": "thesis"})
    assert job.status_code == 201, job.text
    assert job.json()["fidelity"] == "thesis" and job.json()["spec"]["fidelity"] == "thesis"


def test_creation_shows_the_cost_in_the_rig_and_resolution_and_refuses_over_the_limit_naming_it(db_url):
    """The estimate is the cost model's: as measured, the thesis aggregate fills the 590 mm box with the thesis
    preset's packing; at sizes x 2 an eighth of it (1/s^3). Over DEMCAL_MAX_PARTICLES the refusal names
    ``resolution``, the field that lowers the count."""
    from conftest_s2 import running_app, s2_settings

    from engine.lab.cost import estimated_particles
    from engine.lab.rigs import bundled_rig, rig_json
    from engine.lab.spec import JobSpec

    thesis_count = estimated_particles(JobSpec(fidelity="thesis"))
    settings = s2_settings(db_url).model_copy(update={"max_particles": thesis_count - 1})
    with running_app(settings) as (client, _):
        material_id = thesis_material_id(client)
        coarse = client.post(f"{API}/campaigns", json=campaign_body(
            material_id, resolution={"mode": "coarse", "scale_factor": 2.0}, design={"type": "full", "centre_runs": 1}))
        assert coarse.status_code == 201, coarse.text
        estimate = coarse.json()["estimate"]
        assert estimate["rig"] == THESIS_RIG and estimate["resolution"] == "coarse" and estimate["scale_factor"] == 2.0
        assert estimate["particles"] == pytest.approx(thesis_count / 8, abs=1) and estimate["batteries"] == 2 ** 3 + 1
        assert client.get(f"{API}/campaigns/{coarse.json()['id']}").json()["estimate"] == estimate  # and when read
        # x 2 puts 84 mm grains in the 590 mm box (7.0 across): accepted, with the standards' warning
        assert any("shear_box.container_diameter_m" in w and "7.0 largest particles" in w
                   for w in coarse.json()["warnings"]), coarse.json()["warnings"]
        refused = client.post(f"{API}/campaigns", json=campaign_body(material_id, resolution="as_measured"))
        assert refused.status_code == 422 and _loc(refused) == ["body", "resolution"], refused.text
        assert f"about {thesis_count} particles" in refused.text
        record = rig_json(bundled_rig(THESIS_RIG))
        particles = client.get(f"{API}/materials/{material_id}").json()["particles"]
        job = client.post(f"{API}/jobs", json={"evaluator": "analytic", "test": "fill", "rig": record,
                                               "particles": particles, "resolution": {"mode": "coarse",
                                                                                      "scale_factor": 2.0}})
        assert job.status_code == 201, job.text
        assert job.json()["estimate"]["particles"] == estimate["particles"] and job.json()["fidelity"] == "coarse"
        assert job.json()["estimate"]["stages_s"].keys() == {"fill"}
        refused = client.post(f"{API}/jobs", json={"evaluator": "analytic", "test": "fill", "rig": record,
                                                   "particles": particles, "resolution": "as_measured"})
        assert refused.status_code == 422 and _loc(refused) == ["body", "resolution"], refused.text


def test_a_preset_job_is_stored_as_before_resolutions_existed(s2):
    """A job stored by an older version has no resolution, rig or particles; resubmitting it with its idempotency
    key must find it the same job, so a preset job's stored spec leaves the unset fields out."""
    client, app, _ = s2
    from service.models.job import Job

    body = {"evaluator": "analytic", "test": "fill", "fidelity": "thesis", "idempotency_key": "before"}
    first = client.post(f"{API}/jobs", json=body).json()
    assert not {"resolution", "rig", "particles"} & set(first["spec"])
    with app.state.session_factory() as session:  # as an older version stored it
        job = session.get(Job, first["id"])
        assert set(job.spec) == {"test", "fidelity", "seed", "parameters", "options"}
    again = client.post(f"{API}/jobs", json=body)
    assert again.status_code == 200 and again.json()["id"] == first["id"]


def test_the_next_iteration_may_change_the_resolution_and_reuses_none_of_the_other_s_batteries(s2):
    """POST .../iterations {"resolution": ...}: from the 400 mm preset to the material's own 590 mm box, coarse
    x 1.3. The runs follow into the material's rig with its particles, the bulk mass (left out in the 400 mm box)
    becomes a target, and no battery of the other set-up is reused (it simulated another box)."""
    client, app, settings = s2
    body = campaign_body(thesis_material_id(client), fidelity="screening", targets=MEASURED_IN_THE_BOX,
                         design={"type": "full", "centre_runs": 2})
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    nxt = client.post(f"{API}/campaigns/{cid}/iterations", json={"resolution": {"mode": "coarse", "scale_factor": 1.3}})
    assert nxt.status_code == 201, nxt.text
    assert nxt.json()["fidelity"] == "coarse" and nxt.json()["config"]["rig"]["name"] == THESIS_RIG
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    second = client.get(f"{API}/campaigns/{cid}/iterations/2").json()
    assert second["runs"] and not any(r.get("reused_from") for r in second["runs"])
    assert second["report"]["left_out_targets"] == []
    assert "bulk_mass_kg" in {r["quantity"] for r in second["report"]["targets"]}
    # back to a preset: its own rig again (the material's is dropped), bulk mass left out once more
    back = client.post(f"{API}/campaigns/{cid}/iterations", json={"resolution": "screening"})
    assert back.status_code == 201 and back.json()["config"]["rig"] is None and back.json()["fidelity"] == "screening"
    bad = client.post(f"{API}/campaigns/{cid}/iterations", json={"resolution": {"mode": "coarse", "scale_factor": 0.5}})
    assert bad.status_code in (409, 422)
