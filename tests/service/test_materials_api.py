"""Materials and measurements API: bundled thesis material, SI at the edge, error paths."""
from __future__ import annotations

import math
import statistics

import pytest

from conftest_s2 import API, THESIS_MATERIAL, editable_thesis_copy, error_loc, s2, thesis_material_id  # noqa: F401
from service.materials import seed_bundled_materials

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)


def _measurement(material: dict, test: str, quantity: str, **condition) -> dict:
    found = [m for m in material["measurements"] if m["test"] == test and m["quantity"] == quantity
             and all(math.isclose(m["condition"].get(k, math.nan), v) for k, v in condition.items())]
    assert len(found) == 1, (test, quantity, condition)
    return found[0]


def test_bundled_thesis_material_carries_the_published_values(s2):
    client, _, _ = s2
    material = client.get(f"{API}/materials/{thesis_material_id(client)}").json()
    assert material["bundled"] is True
    density = _measurement(material, "fill", "bulk_density_kg_m3")
    assert density["values"] == [1412.0, 1383.6, 1397.8]  # Table 4.5, runs 1-3
    assert density["unit"] == "kg/m3"
    assert density["mean"] == pytest.approx(1397.8, abs=0.05)  # Table 4.5 average
    # standard uncertainty of the mean of three replicates: s / sqrt(3)
    assert density["standard_uncertainty"] == pytest.approx(
        statistics.stdev([1412.0, 1383.6, 1397.8]) / math.sqrt(3))
    porosity = _measurement(material, "fill", "porosity")  # given in % in Table 4.5, stored as a fraction
    assert porosity["values"] == pytest.approx([0.454, 0.465, 0.459])
    modulus = _measurement(material, "cct", "confined_modulus_pa")
    assert modulus["values"] == [8.69e6] and modulus["reported_replicates"] == 3
    assert modulus["standard_uncertainty"] is None  # replicates not printed: nothing to derive
    assert _measurement(material, "dst", "friction_angle_deg")["mean"] == 60.6
    assert _measurement(material, "dst", "dilatancy_angle_deg")["mean"] == 13.2
    aor = _measurement(material, "aor", "angle_of_repose_deg")
    assert aor["values"] == [36.8, 38.5, 33.6, 37.5, 46.1, 40.4, 47.3, 41.1]  # Table 5.1
    anchor_c = _measurement(material, "anchor", "peak_pull_force_n", packing_height_m=0.32, pull_speed_m_s=0.027)
    assert anchor_c["mean"] == 652.6  # Table 5.5, combination C
    assert material["direct_estimates"]["particle_density_kg_m3"]["value"] == 2586.5


def test_seeding_is_idempotent(s2):
    _, app, _ = s2
    with app.state.session_factory() as session:
        first = seed_bundled_materials(session)
        again = seed_bundled_materials(session)
    assert first == again
    names = [m["name"] for m in s2[0].get(f"{API}/materials").json()["items"]]
    assert names.count(THESIS_MATERIAL) == 1


def test_create_material_converts_units_to_si(s2):
    client, _, _ = s2
    body = {"name": "sand", "measurements": [
        {"test": "dst", "quantity": "residual_shear_stress_pa", "unit": "kPa", "values": [17.0, 18.0],
         "condition": {"normal_stress_pa": 24.0}, "condition_units": {"normal_stress_pa": "kPa"}},
        {"test": "cct", "quantity": "confined_modulus_pa", "unit": "MPa", "values": [8.0, 9.0, 10.0]},
        {"test": "aor", "quantity": "angle_of_repose_deg", "unit": "rad", "values": [math.pi / 4]},
    ]}
    response = client.post(f"{API}/materials", json=body)
    assert response.status_code == 201, response.text
    material = response.json()
    shear = _measurement(material, "dst", "residual_shear_stress_pa", normal_stress_pa=24000.0)
    assert shear["values"] == [17000.0, 18000.0] and shear["unit"] == "Pa" and shear["input_unit"] == "kPa"
    assert shear["standard_uncertainty"] == pytest.approx(500.0)  # s = 707.1 Pa, / sqrt(2)
    assert _measurement(material, "cct", "confined_modulus_pa")["mean"] == pytest.approx(9.0e6)
    assert _measurement(material, "aor", "angle_of_repose_deg")["values"][0] == pytest.approx(45.0)

    added = client.post(f"{API}/materials/{material['id']}/measurements", json={
        "test": "fill", "quantity": "bulk_density_kg_m3", "unit": "g/cm3", "values": [1.4],
        "standard_uncertainty": 0.01})
    assert added.status_code == 201
    assert added.json()["values"] == [pytest.approx(1400.0)]
    assert added.json()["standard_uncertainty"] == pytest.approx(10.0)
    listed = client.get(f"{API}/materials/{material['id']}/measurements").json()["items"]
    assert len(listed) == 4
    assert client.delete(f"{API}/materials/{material['id']}/measurements/{added.json()['id']}").status_code == 204
    assert len(client.get(f"{API}/materials/{material['id']}/measurements").json()["items"]) == 3
    assert client.delete(f"{API}/materials/{material['id']}").status_code == 204
    assert client.get(f"{API}/materials/{material['id']}").status_code == 404


@pytest.mark.parametrize("measurement, loc", [
    ({"test": "shear", "quantity": "friction_angle_deg", "values": [1.0]}, ["body", "test"]),
    ({"test": "dst", "quantity": "bulk_density_kg_m3", "values": [1.0]}, ["body", "quantity"]),
    ({"test": "dst", "quantity": "friction_angle_deg", "unit": "kPa", "values": [1.0]}, ["body", "unit"]),
    ({"test": "dst", "quantity": "friction_angle_deg", "values": []}, ["body", "values"]),
    ({"test": "dst", "quantity": "residual_shear_stress_pa", "values": [1.0], "condition": {"load": 3.0}},
     ["body", "condition", "load"]),
    ({"test": "dst", "quantity": "residual_shear_stress_pa", "values": [1.0],
      "condition": {"normal_stress_pa": 3.0}, "condition_units": {"normal_stress_pa": "deg"}},
     ["body", "condition", "normal_stress_pa"]),
])
def test_bad_measurements_are_422_naming_the_field(s2, measurement, loc):
    client, _, _ = s2
    material_id = editable_thesis_copy(client)
    response = client.post(f"{API}/materials/{material_id}/measurements", json=measurement)
    assert response.status_code == 422
    assert error_loc(response)[:len(loc)] == loc


def test_material_errors(s2):
    client, _, _ = s2
    material_id = editable_thesis_copy(client)
    assert client.get(f"{API}/materials/999").status_code == 404
    assert error_loc(client.get(f"{API}/materials/999")) == ["path", "material_id"]
    assert client.get(f"{API}/materials/999/measurements").status_code == 404
    assert client.post(f"{API}/materials/999/measurements", json={
        "test": "dst", "quantity": "friction_angle_deg", "values": [1.0]}).status_code == 404
    missing = client.delete(f"{API}/materials/{material_id}/measurements/99999")
    assert missing.status_code == 404 and error_loc(missing) == ["path", "measurement_id"]
    duplicate = client.post(f"{API}/materials", json={"name": THESIS_MATERIAL})
    assert duplicate.status_code == 409 and error_loc(duplicate) == ["body", "name"]
    nested = client.post(f"{API}/materials", json={"name": "m", "measurements": [
        {"test": "dst", "quantity": "friction_angle_deg", "values": [1.0], "unit": "N"}]})
    assert nested.status_code == 422 and error_loc(nested) == ["body", "measurements", "0", "unit"]
    assert client.post(f"{API}/materials", json={"name": ""}).status_code == 422
    assert client.delete(f"{API}/materials/999").status_code == 404


def test_material_used_by_a_campaign_cannot_be_deleted(s2):
    from conftest_s2 import campaign_body

    client, _, _ = s2
    # a campaign needs a measurement to calibrate against (an empty material is refused at creation)
    material = client.post(f"{API}/materials", json={"name": "used", "measurements": [
        {"test": "fill", "quantity": "bulk_density_kg_m3", "values": [1400.0]}]}).json()
    assert client.post(f"{API}/campaigns", json=campaign_body(material["id"])).status_code == 201
    response = client.delete(f"{API}/materials/{material['id']}")
    assert response.status_code == 409 and error_loc(response) == ["path", "material_id"]


def test_quantities_lists_si_and_accepted_units(s2):
    client, _, _ = s2
    table = client.get(f"{API}/materials/quantities").json()
    assert table["dst"]["residual_shear_stress_pa"]["si_unit"] == "Pa"
    assert "kPa" in table["dst"]["residual_shear_stress_pa"]["accepted_units"]


def _shear(value: float, unit: str) -> dict:
    return {"test": "dst", "quantity": "residual_shear_stress_pa", "unit": "kPa", "values": [17.0, 18.0],
            "condition": {"normal_stress_pa": value}, "condition_units": {"normal_stress_pa": unit}}


@pytest.mark.parametrize("first, second", [
    ((24.0, "kPa"), (24000.0, "Pa")),
    # 0.0243 kPa converts to 24.299999999999997 Pa: not the float 24.3, the same condition
    ((24.3, "Pa"), (0.0243, "kPa")),
])
def test_a_measurement_with_the_key_of_a_stored_one_is_refused_naming_it(s2, first, second):
    """One key (calibration.keys.ResponseKey, with its tolerance) decides what the calibration matches and
    what storage holds once: the same test, quantity and condition in other units is the same measurement."""
    client, _, _ = s2
    material_id = client.post(f"{API}/materials", json={"name": "sand"}).json()["id"]
    stored = client.post(f"{API}/materials/{material_id}/measurements", json=_shear(*first))
    assert stored.status_code == 201, stored.text
    again = client.post(f"{API}/materials/{material_id}/measurements", json=_shear(*second))
    assert again.status_code == 422 and error_loc(again) == ["body", "condition"]
    assert f"measurement {stored.json()['id']}" in again.json()["detail"][0]["msg"]
    assert len(client.get(f"{API}/materials/{material_id}/measurements").json()["items"]) == 1
    in_one_body = client.post(f"{API}/materials", json={"name": "gravel", "measurements": [_shear(*first),
                                                                                        _shear(*second)]})
    assert in_one_body.status_code == 422 and error_loc(in_one_body) == ["body", "measurements", "1", "condition"]


def test_measurements_at_different_conditions_are_both_stored(s2):
    client, _, _ = s2
    material_id = client.post(f"{API}/materials", json={"name": "sand"}).json()["id"]
    for value in (24.0, 25.0):
        response = client.post(f"{API}/materials/{material_id}/measurements", json=_shear(value, "kPa"))
        assert response.status_code == 201, response.text
    stresses = sorted(m["condition"]["normal_stress_pa"]
                      for m in client.get(f"{API}/materials/{material_id}/measurements").json()["items"])
    assert stresses == [24000.0, 25000.0]
