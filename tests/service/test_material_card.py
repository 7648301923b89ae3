"""The neutral material card (issue 30 item 1): a calibrated campaign as one documented file, imported back
as a material with fixed parameters, card -> material -> card to identical bytes.

Campaigns run on the analytic evaluator (a whole iteration in about a second)."""
from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import pytest
import yaml

from conftest_s2 import API, campaign_body, run_to_end, running_app, s2, s2_settings, thesis_material_id  # noqa: F401
from test_campaign_cli import run, server  # noqa: F401  (the CLI against a real HTTP server)

from engine.lab.spec import MicroParameters
from service.export import formats
from service.export.card import load_text


def _calibrated(client, app, settings, **overrides) -> int:
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), **overrides)).json()["id"]
    assert client.post(f"{API}/campaigns/{cid}/start").status_code == 200
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    return cid


@pytest.fixture
def calibrated(s2):
    """A calibrated thesis campaign with rolling resistance fixed."""
    client, app, settings = s2
    fixed = {"effects": {"rolling_epsd2": {"rolling_friction": 0.2}}}
    return client, app, settings, _calibrated(client, app, settings, fixed_parameters=fixed)


def test_the_card_states_the_calibrated_material_in_si_with_units(calibrated):
    client, _, _, cid = calibrated
    card = client.get(f"{API}/campaigns/{cid}/material-card").json()
    report = client.get(f"{API}/campaigns/{cid}/report").json()
    assert card["card_version"] == 1 and card["format"] == "demcal material card" and card["demcal_version"]
    assert card["material"]["name"] == "thesis-coarse-aggregate"
    # the calibrated values are the report's optimum, each where the engine uses it, with its SI unit
    optimum = report["optimum"]
    density = card["particles"]["parameters"]["particle_density_kg_m3"]
    assert density == {"value": optimum["particle_density_kg_m3"], "unit": "kg/m3", "description": density["description"]}
    stiffness = card["contact"]["parameters"]["particle_stiffness_n_per_m"]
    assert (stiffness["value"], stiffness["unit"]) == (optimum["particle_stiffness_n_per_m"], "N/m")
    assert card["contact"]["parameters"]["friction_pp"]["value"] == optimum["friction_pp"]
    assert card["contact"]["parameters"]["friction_pp"]["unit"] == "1"
    # the parameters the campaign did not vary are demcal's defaults, stated all the same
    assert card["contact"]["parameters"]["damping_ratio"]["value"] == MicroParameters().damping_ratio
    assert card["contact"]["law"] == "linear_spring_dashpot_pfc" and "series" in card["contact"]["description"]
    calibrated = {p["name"]: p for p in card["calibration"]["parameters"]}
    assert set(calibrated) == set(optimum)
    assert calibrated["friction_pp"]["design_range"] == [0.3, 1.0]
    assert calibrated["particle_density_kg_m3"]["standard_uncertainty"] > 0
    assert card["calibration"]["verdict"] == report["verdict"] and card["calibration"]["iteration"] == 1
    assert card["calibration"]["evaluator"] == "analytic"

    # the thesis rig's grains (Table 4.2): volume shares 37.5 / 41.7 / 20.8 %, sphere radii in mm ranges
    shapes = {s["shape"]: s for s in card["particles"]["shapes"]}
    assert [shapes[k]["volume_fraction"] for k in ("pyramid", "double_clump", "sphere")] == [0.375, 0.417, 0.208]
    assert shapes["pyramid"]["radius_distribution"]["radius_min_m"] == 0.0075
    assert shapes["sphere"]["radius_distribution"]["radius_max_m"] == 0.0162
    # four touching spheres (tetrahedron of edge 2 r) do not overlap: the body is 4 spheres' volume
    r = 0.0105
    pyramid = shapes["pyramid"]
    assert pyramid["reference_volume_m3"] == pytest.approx(4 * 4 / 3 * math.pi * r**3, rel=1e-9)
    centres = [s["centre_m"] for s in pyramid["reference_spheres"]]
    assert math.dist(centres[0], centres[1]) == pytest.approx(2 * r, rel=1e-12)
    # a touching double clump of 15 mm spheres is 60 mm long: the 590 mm box is 9.83 grains across
    assert card["rig"]["fidelity"] == "thesis"
    assert card["rig"]["container_diameter_in_largest_grains"] == pytest.approx(0.590 / 0.060, rel=1e-12)

    # provenance: the targets with their replicates (SI) and the calibrated model's result
    fill = next(m for m in card["measurements"] if m["test"] == "fill")
    assert fill["values"] == [1412.0, 1383.6, 1397.8] and fill["unit"] == "kg/m3"
    assert fill["source"].startswith("Table 4.5")
    row = next(t for t in report["targets"] if t["test"] == "fill")
    assert fill["result"]["confirmed"] == row["confirmed"]
    assert fill["result"]["prediction_interval"] == row["prediction_interval"]
    assert [m["test"] for m in card["measurements"]] == ["fill", "cct", "dst"]  # the campaign's targets only


def test_effects_and_clumps_are_stated_with_every_parameter(s2):
    """A screening campaign with two-sphere clumps and two contact effects fixed: every effect parameter
    appears with its unit, defaults included (Poisson's ratio), and the clump's body is the engine's."""
    client, app, settings = s2
    fixed = {"clump_aspect_ratio": 1.5, "effects": {"rolling_epsd2": {"rolling_friction": 0.1},
                                                    "cohesion_adhesive": {"surface_energy_j_m2": 2.0}}}
    cid = _calibrated(client, app, settings, fidelity="screening", fixed_parameters=fixed)
    card = client.get(f"{API}/campaigns/{cid}/material-card").json()
    effects = card["contact"]["effects"]
    assert effects["rolling_epsd2"]["stage"] == "rolling"
    assert effects["rolling_epsd2"]["parameters"]["rolling_friction"]["value"] == 0.1
    assert effects["rolling_epsd2"]["parameters"]["rolling_friction"]["unit"] == "1"
    assert effects["cohesion_adhesive"]["parameters"]["surface_energy_j_m2"]["unit"] == "J/m2"
    assert card["calibration"]["fixed_by_campaign"] == ["clump_aspect_ratio", "effects"]
    (shape,) = card["particles"]["shapes"]
    assert shape["shape"] == "custom" and len(shape["reference_spheres"]) == 2
    # two equal spheres of radius r, centres d = 2 r (a - 1) apart: length / width = (d + 2 r) / (2 r) = 1.5
    a, b = shape["reference_spheres"]
    length = math.dist(a["centre_m"], b["centre_m"]) + 2 * a["radius_m"]
    assert length / (2 * a["radius_m"]) == pytest.approx(1.5, rel=1e-9)
    # ... of the solid volume of the 20 mm screening sphere it replaces (engine/lab/shape.py)
    assert shape["reference_volume_m3"] == pytest.approx(4 / 3 * math.pi * 0.020**3, rel=1e-9)
    assert card["particles"]["parameters"]["clump_aspect_ratio"]["value"] == 1.5


def test_card_to_material_to_card_is_the_same_bytes(s2, tmp_path):
    """Exported on one installation, imported on another (the name is free there), exported again: the
    same file, in JSON and in YAML; the imported material has the card's fixed parameters and targets."""
    client, app, settings = s2
    fixed = {"effects": {"rolling_epsd2": {"rolling_friction": 0.2}}}
    cid = _calibrated(client, app, settings, fixed_parameters=fixed)
    as_json = client.get(f"{API}/campaigns/{cid}/material-card").content
    as_yaml = client.get(f"{API}/campaigns/{cid}/material-card", headers={"Accept": "application/yaml"}).content
    assert as_yaml == client.get(f"{API}/campaigns/{cid}/material-card?format=yaml").content
    assert yaml.safe_load(as_yaml) == json.loads(as_json)

    (tmp_path / "elsewhere").mkdir()
    # another installation, without the bundled material (whose name the card carries)
    elsewhere = s2_settings(tmp_path / "elsewhere").model_copy(update={"seed_materials": False})
    with running_app(elsewhere) as (other, _):
        response = other.post(f"{API}/materials/import-card", json=load_text(as_yaml.decode()))
        assert response.status_code == 201, response.text
        material = response.json()
        assert material["name"] == "thesis-coarse-aggregate" and not material["bundled"]
        assert [(m["test"], m["quantity"], m["values"]) for m in material["measurements"]] == \
            [(m["test"], m["quantity"], m["values"]) for m in json.loads(as_json)["measurements"]]
        fixed_parameters = material["direct_estimates"]["material_card"]["fixed_parameters"]
        assert fixed_parameters["effects"] == {"rolling_epsd2": {"rolling_friction": 0.2}}
        assert fixed_parameters["friction_pp"] == json.loads(as_json)["contact"]["parameters"]["friction_pp"]["value"]
        mid = material["id"]
        assert other.get(f"{API}/materials/{mid}/material-card").content == as_json
        assert other.get(f"{API}/materials/{mid}/material-card?format=yaml").content == as_yaml
        # a measurement deleted since: the others keep their own results
        first = material["measurements"][0]["id"]
        assert other.delete(f"{API}/materials/{mid}/measurements/{first}").status_code == 204
        assert other.get(f"{API}/materials/{mid}/material-card").json()["measurements"] == \
            json.loads(as_json)["measurements"][1:]
        # a second import of the same card: the name is taken
        again = other.post(f"{API}/materials/import-card", json=json.loads(as_json))
        assert again.status_code == 409 and again.json()["detail"][0]["loc"] == ["body", "name"]
        renamed = other.post(f"{API}/materials/import-card", json=json.loads(as_json), params={"name": "copy"})
        assert renamed.status_code == 201 and renamed.json()["name"] == "copy"


def test_a_campaign_not_calibrated_yet_answers_409(s2):
    client, _, _ = s2
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
    for path in ("material-card", "export?format=card", "report.html"):
        response = client.get(f"{API}/campaigns/{cid}/{path}")
        assert response.status_code == 409, (path, response.text)
        assert "not calibrated yet" in response.json()["detail"][0]["msg"]
    assert client.get(f"{API}/campaigns/987654/material-card").status_code == 404
    # a material that was not imported from a card has no calibrated values to state
    response = client.get(f"{API}/materials/{thesis_material_id(client)}/material-card")
    assert response.status_code == 409 and "not imported from a material card" in response.text


def _edit(card: dict, path: str, value) -> dict:
    out = copy.deepcopy(card)
    *parents, last = path.split(".")
    node = out
    for key in parents:
        node = node[int(key)] if isinstance(node, list) else node[key]
    if value is _DELETE:
        del node[last]
    else:
        node[last] = value
    return out


_DELETE = object()


BAD_CARDS = [
    ("card_version", 2, ["body", "card_version"]),
    ("contact.parameters.friction_pp.value", -0.1, ["body", "contact", "parameters", "friction_pp"]),
    ("contact.parameters.friction_pp.value", "0.5", ["body", "contact", "parameters", "friction_pp", "value"]),
    ("particles.parameters.particle_density_kg_m3.unit", "g/cm3",
     ["body", "particles", "parameters", "particle_density_kg_m3", "unit"]),
    ("contact.effects.rolling_epsd2.parameters.rolling_friction.value", -1.0,
     ["body", "contact", "effects", "rolling_epsd2", "parameters", "rolling_friction", "value"]),
    ("contact.effects.rolling_epsd2.parameters.rolling_friction.unit", "rad",
     ["body", "contact", "effects", "rolling_epsd2", "parameters", "rolling_friction", "unit"]),
    ("contact.effects.rolling_sticky", {"stage": "rolling", "parameters": {}}, ["body", "contact", "effects", "rolling_sticky"]),
    ("contact.parameters.young_modulus_pa", {"value": 1e9, "unit": "Pa"},
     ["body", "contact", "parameters", "young_modulus_pa"]),
    ("particles.shapes.0.volume_fraction", 0.5, ["body", "particles", "shapes"]),
    ("rig.fidelity", "screening", ["body", "particles", "shapes"]),
    ("rig.fidelity", "production", ["body", "rig", "fidelity"]),
    ("measurements.0.quantity", "bulk_density", ["body", "measurements", 0, "quantity"]),
    ("measurements.0.unit", "g/cm3", ["body", "measurements", 0, "unit"]),
    ("measurements.0.values", [], ["body", "measurements", 0, "values"]),
    ("measurements.0.values", [1412.0, -5.0], ["body", "measurements", 0, "values", 1]),
]


def test_a_bad_card_is_a_422_naming_the_field_and_stores_nothing(calibrated):
    client, _, _, cid = calibrated
    good = json.loads(client.get(f"{API}/campaigns/{cid}/material-card").content)
    good["material"]["name"] = "imported"
    before = client.get(f"{API}/materials").json()
    for path, value, loc in BAD_CARDS:
        response = client.post(f"{API}/materials/import-card", json=_edit(good, path, value))
        assert response.status_code == 422, (path, response.text)
        got = response.json()["detail"][0]["loc"]
        assert got[:len(loc)] == loc, (path, got, response.json())
    assert client.get(f"{API}/materials").json() == before
    # a parameter left out is the engine's default, and the card says so when exported again
    response = client.post(f"{API}/materials/import-card", json=_edit(good, "contact.parameters.friction_pw", _DELETE))
    assert response.status_code == 201, response.text
    assert response.json()["direct_estimates"]["material_card"]["fixed_parameters"]["friction_pw"] == \
        MicroParameters().friction_pw


def test_not_a_card_is_a_422(s2):
    client, _, _ = s2
    for body, loc in (({"card_version": 1}, ["body", "demcal_version"]), ([1, 2], ["body"])):
        response = client.post(f"{API}/materials/import-card", json=body)
        assert response.status_code == 422 and response.json()["detail"][0]["loc"][:len(loc)] == loc, response.text


def test_export_formats_are_a_registry(calibrated):
    """Every registered format is served from the card alone; an unknown one is a 422 listing them."""
    client, _, _, cid = calibrated
    listed = {f["name"]: f for f in client.get(f"{API}/export-formats").json()}
    assert {"card", "card-json", "liggghts"} <= set(listed) and set(listed) == set(formats.names())
    card = client.get(f"{API}/campaigns/{cid}/material-card").json()
    for name, fmt in listed.items():
        response = client.get(f"{API}/campaigns/{cid}/export", params={"format": name})
        assert response.status_code == 200
        assert response.headers["content-type"].startswith(fmt["media_type"])
        assert f'campaign-{cid}{fmt["suffix"]}' in response.headers["content-disposition"]
        assert response.text == formats.get(name).render(card)
    bad = client.get(f"{API}/campaigns/{cid}/export", params={"format": "step"})
    assert bad.status_code == 422 and bad.json()["detail"][0]["loc"] == ["query", "format"]
    assert "card-json" in bad.json()["detail"][0]["msg"]


def test_cli_exports_the_card_and_imports_it(server, capsys, tmp_path: Path):
    url, app, settings = server
    from conftest_s2 import drain
    from service.campaigns.runner import CampaignRunner
    import httpx

    body = campaign_body(1)
    cid = httpx.post(f"{url}{API}/campaigns", json=body).json()["id"]
    code, _, err = run(capsys, "campaign", "export", str(cid), "--url", url, "--format", "card")
    assert code == 2 and "HTTP 409" in err and "not calibrated yet" in err
    httpx.post(f"{url}{API}/campaigns/{cid}/start")
    runner = CampaignRunner(app.state.session_factory, settings)
    for _ in range(20):
        runner.tick()
        drain(app, settings)
        if httpx.get(f"{url}{API}/campaigns/{cid}").json()["status"] == "completed":
            break
    card_file = tmp_path / "material.card.yaml"
    code, _, err = run(capsys, "campaign", "export", str(cid), "--url", url, "--format", "card", "--output", str(card_file))
    assert code == 0 and "written to" in err
    assert card_file.read_bytes() == httpx.get(f"{url}{API}/campaigns/{cid}/material-card?format=yaml").content
    code, out, _ = run(capsys, "campaign", "export", str(cid), "--url", url, "--format", "card-json")
    assert code == 0 and json.loads(out)["calibration"]["campaign_id"] == cid
    code, _, err = run(capsys, "campaign", "export", str(cid), "--url", url, "--format", "step")
    assert code == 2 and "unknown export format 'step'" in err

    code, out, _ = run(capsys, "material", "import-card", str(card_file), "--url", url, "--name", "from card", "-q")
    assert code == 0
    mid = int(out.strip())
    code, out, _ = run(capsys, "material", "card", str(mid), "--url", url)
    assert code == 0 and out == card_file.read_text().replace("name: thesis-coarse-aggregate", "name: from card", 1)
    bad = tmp_path / "bad.yaml"
    bad.write_text("card_version: 1\nformat: [unclosed\n")
    code, _, err = run(capsys, "material", "import-card", str(bad), "--url", url)
    assert code == 2 and "not YAML or JSON" in err and "Traceback" not in err
    bad.write_text(card_file.read_text().replace("unit: N/m", "unit: kN/m", 1))
    code, _, err = run(capsys, "material", "import-card", str(bad), "--url", url, "--name", "bad")
    assert code == 2 and "HTTP 422" in err and "particle_stiffness_n_per_m.unit" in err


def test_a_card_of_given_parameters_round_trips_too(s2):
    """``parameters_card``: no calibration behind it (an export format's tests start from one)."""
    from service.export.card import dump_json, parameters_card

    client, _, _ = s2
    params = MicroParameters(friction_pp=0.5, particle_radius_m=0.015,
                             effects={"hertz_mindlin": {"young_modulus_pa": 5e8}})
    card = parameters_card(params, name="given", demcal_version="test")
    assert card["calibration"] is None and card["measurements"] == []
    hertz = card["contact"]["effects"]["hertz_mindlin"]["parameters"]
    # every parameter stated, the defaults too (Poisson's ratio 0.25; no separate wall modulus)
    assert {k: (v["value"], v["unit"]) for k, v in hertz.items()} == {
        "young_modulus_pa": (5e8, "Pa"), "poisson_ratio": (0.25, "1"), "wall_young_modulus_pa": (None, "Pa"),
        "wall_poisson_ratio": (None, "1")}
    # 15 mm screening spheres: the 400 mm container is 400 / 30 = 13.3 grains across
    assert card["rig"]["container_diameter_in_largest_grains"] == pytest.approx(0.400 / 0.030, rel=1e-12)
    response = client.post(f"{API}/materials/import-card", json=card)
    assert response.status_code == 201, response.text
    assert client.get(f"{API}/materials/{response.json()['id']}/material-card").text == dump_json(card)


def test_the_default_card_is_the_model_the_loop_keeps():
    """The automatic mode rejected the effect iteration 2 added (or turned it off in the noise, or compared an
    alias): the card, the export and the HTML report default to the model it keeps, never the rejected one."""
    from types import SimpleNamespace

    from service.export.store import calibrated_iteration

    def campaign(record):
        first = SimpleNamespace(number=1, report={"verdict": "model misses the measurements"}, phase="done")
        second = SimpleNamespace(number=2, report={"automatic": record}, phase="done")
        return SimpleNamespace(id=1, iterations=[first, second], current_iteration=2, status="completed")

    rejected = {"decision": {"accepted": False}, "base_iteration": 1, "stop_reason": "nothing improves"}
    assert calibrated_iteration(campaign(rejected)).number == 1
    assert calibrated_iteration(campaign(rejected), 2).number == 2  # asked for by number: that one
    turned_off = {"decision": {"accepted": False, "turned_off": True}, "base_iteration": 1, "kept_iteration": 2}
    assert calibrated_iteration(campaign(turned_off)).number == 2
    accepted = {"decision": {"accepted": True}, "base_iteration": 1, "stop_reason": "lack of fit passes"}
    assert calibrated_iteration(campaign(accepted)).number == 2
    assert calibrated_iteration(campaign({})).number == 2  # not automatic: the latest report


def test_an_effect_turned_off_leaves_the_card_of_the_kept_base_model():
    """Tier B's weak Hertz world (session 35): the loop added cohesion, the polish put its surface energy at
    3e-12 J/m2 against an off value of 0 and the iteration was kept as the base model refitted. Its card must
    not hand LIGGGHTS a cohesion model in name only: the effect, its factor, interval and trades leave, the
    meaning says why, and every other value stays as fitted."""
    from service.export.store import without_turned_off

    energy = "effects.cohesion_adhesive.surface_energy_j_m2"
    report = {"optimum": {"friction_pp": 0.58, energy: 3e-12}, "meaning": "lack of fit passes.",
              "fixed_parameters": {"density_kg_m3": 2650.0},
              "intervals": {"parameters": {"friction_pp": {"low": 0.5, "high": 0.66, "sd": 0.04},
                                           energy: {"low": 0.0, "high": 2.0, "sd": 1.0}},
                            "trades": [{"parameters": ["friction_pp", energy], "correlation": -0.93,
                                        "message": "friction_pp and surface energy trade"}]},
              "automatic": {"decision": {"effect": "cohesion_adhesive", "accepted": False, "turned_off": True},
                            "base_iteration": 1, "kept_iteration": 2}}
    factors = [{"name": "friction_pp", "low": 0.2, "high": 0.9}, {"name": energy, "low": 0.0, "high": 40.0}]
    card_report, card_factors = without_turned_off(2, report, factors)
    assert card_report["optimum"] == {"friction_pp": 0.58}
    assert list(card_report["intervals"]["parameters"]) == ["friction_pp"] and card_report["intervals"]["trades"] == []
    assert [f["name"] for f in card_factors] == ["friction_pp"]
    assert card_report["fixed_parameters"] == {"density_kg_m3": 2650.0}
    assert "cohesion_adhesive was fitted at its off strength (surface_energy_j_m2 3e-12)" in card_report["meaning"]
    assert report["optimum"][energy] == 3e-12  # the stored report itself is untouched
    # asked for as iteration 3 (not the kept one), or accepted, or not turned off: the card is as fitted
    assert without_turned_off(3, report, factors) == (report, factors)
    accepted = {**report, "automatic": {"decision": {"effect": "cohesion_adhesive", "accepted": True}}}
    assert without_turned_off(2, accepted, factors) == (accepted, factors)
