"""Rigs through the API and the CLI: bundled records seeded read-only, users' rigs created, read, listed,
refused naming the field, and checked against a material's particles (a warning for a box too small)."""
from __future__ import annotations

import json

import pytest

from conftest_s2 import API, s2, thesis_material_id  # noqa: F401
from engine.lab.rigs import RECORDS_DIR
from test_campaign_cli import run, server  # noqa: F401  (the loopback uvicorn fixture)

THESIS_RIG = "thesis-590mm-shear-box"
APPENDIX_A_RIG = "appendix-a-400mm-shear-box"


def _thesis_record(name: str = "lab 300 mm box") -> dict:
    body = json.loads((RECORDS_DIR / "thesis_590mm.json").read_text())
    body["name"] = name
    return body


def _rig_id(client, name: str) -> int:
    return next(r["id"] for r in client.get(f"{API}/rigs").json()["items"] if r["name"] == name)


def _gravel(client, rig: str | None = None, name: str = "gravel 8-16 mm") -> dict:
    """A material of 8-16 mm spheres (a sieve curve): 16 mm is the largest particle."""
    body = {"name": name, "particles": {
        "solid_density_kg_m3": 2650.0,
        "size": {"form": "sieve", "sieve_sizes_m": [0.008, 0.0112, 0.016], "passing_fractions": [0.0, 0.5, 1.0]},
        "shapes": [{"shape": "sphere", "volume_fraction": 1.0}]}}
    if rig is not None:
        body["rig"] = rig
    return client.post(f"{API}/materials", json=body)


def test_bundled_rigs_are_seeded_and_the_thesis_material_names_its_rig(s2):
    client, _, _ = s2
    rigs = {r["name"]: r for r in client.get(f"{API}/rigs").json()["items"]}
    assert rigs[THESIS_RIG]["bundled"] and rigs[APPENDIX_A_RIG]["bundled"]
    assert rigs[THESIS_RIG]["shear_box"]["container_diameter_m"] == 0.590  # the thesis's 590 mm box
    assert rigs[APPENDIX_A_RIG]["shear_box"]["container_diameter_m"] == 0.400  # Table A.7: radius 200 mm
    assert rigs[APPENDIX_A_RIG]["shear_box"]["dst_normal_forces_n"] == [1885.0, 3495.0, 5105.0, 6760.0]
    material = client.get(f"{API}/materials/{thesis_material_id(client)}").json()
    assert material["rig"] == THESIS_RIG and material["rig_id"] == rigs[THESIS_RIG]["id"]
    assert [s["shape"] for s in material["particles"]["shapes"]] == ["pyramid", "elongated", "sphere"]
    assert material["warnings"] == []  # the thesis designed its box for its aggregate


def test_create_read_list(s2):
    client, _, _ = s2
    body = _thesis_record()
    body["shear_box"].update(container_diameter_m=0.300, bottom_half_height_m=0.100, top_half_height_m=0.100)
    body["fill"]["level_height_m"] = 0.200
    created = client.post(f"{API}/rigs", json=body)
    assert created.status_code == 201, created.text
    rig = created.json()
    assert rig["bundled"] is False and rig["warnings"] == []
    assert rig["shear_box"]["container_diameter_m"] == 0.300
    shown = client.get(f"{API}/rigs/{rig['id']}").json()
    assert shown["name"] == "lab 300 mm box" and shown["fill"]["level_height_m"] == 0.200
    assert "lab 300 mm box" in [r["name"] for r in client.get(f"{API}/rigs").json()["items"]]
    # a user's rig can be replaced; a second rig of the same name cannot be created
    body["description"] = "measured again"
    assert client.put(f"{API}/rigs/{rig['id']}", json=body).json()["description"] == "measured again"
    assert client.post(f"{API}/rigs", json=body).status_code == 409
    assert client.get(f"{API}/rigs/999").status_code == 404


@pytest.mark.parametrize("section, key, value, loc", [
    ("shear_box", "container_diameter_m", -0.3, ["body", "shear_box", "container_diameter_m"]),
    ("shear_box", "gap_m", 0.2, ["body", "shear_box", "gap_m"]),
    ("shear_box", "max_normal_force_n", 5000.0, ["body", "shear_box", "dst_normal_stresses_pa"]),
    ("anchor", "pull_speed_m_s", 0.0, ["body", "anchor", "pull_speed_m_s"]),
])
def test_bad_rig_is_refused_naming_the_field(s2, section, key, value, loc):
    client, _, _ = s2
    body = _thesis_record()
    body[section][key] = value
    response = client.post(f"{API}/rigs", json=body)
    assert response.status_code == 422
    assert response.json()["detail"][0]["loc"] == loc
    assert "lab 300 mm box" not in [r["name"] for r in client.get(f"{API}/rigs").json()["items"]]


def test_bundled_rig_edit_is_refused(s2):
    client, _, _ = s2
    rig_id = _rig_id(client, THESIS_RIG)
    body = _thesis_record(THESIS_RIG)
    body["shear_box"]["gap_m"] = 0.005
    response = client.put(f"{API}/rigs/{rig_id}", json=body)
    assert response.status_code == 409 and response.json()["detail"][0]["loc"] == ["path", "rig_id"]
    assert client.get(f"{API}/rigs/{rig_id}").json()["shear_box"]["gap_m"] == 0.001


def test_too_small_box_is_accepted_with_a_warning_and_a_gap_particles_fall_through_refused(s2):
    client, _, _ = s2
    material = _gravel(client).json()
    # 120 mm across is 7.5 of the 16 mm particles (< 10); the 200 mm specimen is 12.5 thick (>= 6)
    body = _thesis_record("small box")
    body["shear_box"].update(container_diameter_m=0.120, bottom_half_height_m=0.100, top_half_height_m=0.100)
    body["fill"]["level_height_m"] = 0.200
    created = client.post(f"{API}/rigs", params={"material_id": material["id"]}, json=body)
    assert created.status_code == 201, created.text
    warnings = created.json()["warnings"]
    assert len(warnings) == 1 and warnings[0].startswith("shear_box.container_diameter_m")
    # the material measured in it repeats the warning wherever it is read
    copy = _gravel(client, rig="small box", name="gravel in the small box").json()
    assert copy["warnings"] == warnings
    # a 10 mm gap lets the 8 mm particles through: refused naming the gap
    body = _thesis_record("open gap")
    body["shear_box"]["gap_m"] = 0.010
    refused = client.post(f"{API}/rigs", params={"material_id": material["id"]}, json=body)
    assert refused.status_code == 422 and refused.json()["detail"][0]["loc"] == ["body", "shear_box", "gap_m"]
    small_box = _rig_id(client, "small box")
    check = client.get(f"{API}/rigs/{small_box}/check", params={"material_id": material["id"]})
    assert check.status_code == 200 and check.json()["warnings"] == warnings
    # a rig a material names is no longer edited in place: its measurements were made in it
    body = _thesis_record("small box")
    response = client.put(f"{API}/rigs/{small_box}", json=body)
    assert response.status_code == 409 and "gravel in the small box" in response.json()["detail"][0]["msg"]


def test_material_names_an_unknown_rig_refused(s2):
    client, _, _ = s2
    response = _gravel(client, rig="no such rig")
    assert response.status_code == 422 and response.json()["detail"][0]["loc"] == ["body", "rig"]


def test_rig_cli(server, capsys, tmp_path):
    url, _, _ = server
    code, out, _ = run(capsys, "rig", "list", "--url", url)
    assert code == 0 and THESIS_RIG in out and "590 mm" in out
    code, out, _ = run(capsys, "rig", "show", "2", "--url", url, "--json")
    assert code == 0 and json.loads(out)["name"] in (THESIS_RIG, APPENDIX_A_RIG)
    record = tmp_path / "rig.json"
    record.write_text(json.dumps(_thesis_record("cli rig")))
    code, out, _ = run(capsys, "rig", "create", str(record), "--url", url)
    assert code == 0 and out.startswith("rig 3: cli rig")
    body = _thesis_record("bad rig")
    body["shear_box"]["container_diameter_m"] = -1
    record.write_text(json.dumps(body))
    code, out, err = run(capsys, "rig", "create", str(record), "--url", url)
    assert code == 2 and "container_diameter_m" in err and "Traceback" not in err
