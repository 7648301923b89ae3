"""Issue 31: the unit slips real users make are stored with a warning naming the likely unit, shown at entry
and in the report of every campaign that uses them; the physically impossible is refused, as before.

The slips and the ranges they fall outside are those of docs/lab.md, "Plausible ranges" (cited sources):
each slipped number is a unit factor away from a typical value of a granular material.
"""
from conftest_s2 import API, campaign_body, run_to_end, s2  # noqa: F401

# (measurement as typed, the words its warning must carry)
SLIPS = [
    # 8.69 MPa (the thesis aggregate's confined modulus) typed as 8,690 Pa
    ({"test": "cct", "quantity": "confined_modulus_pa", "values": [8690.0], "unit": "Pa"},
     ["8,690 Pa is below the confined moduli of granular packings", "was it kPa"]),
    # 8.6 MPa typed in Pa but entered with --unit kPa: 8.6 GPa, ten times above the stiffest packings' range
    ({"test": "cct", "quantity": "confined_modulus_pa", "values": [8.6e6], "unit": "kPa",
      "condition": {"normal_stress_pa": 30000.0}},
     ["8.6e+09 Pa is above the confined moduli of granular packings", "was it Pa, 1,000 times less"]),
    # 1.3967 g/cm3 typed as kg/m3
    ({"test": "fill", "quantity": "bulk_density_kg_m3", "values": [1.3967], "unit": "kg/m3"},
     ["1.3967 kg/m3 is below the bulk densities of dry granular materials", "was it g/cm3"]),
    # a residual shear stress of 16.2 kPa at a normal stress of 24 kPa typed as 24 Pa
    ({"test": "dst", "quantity": "residual_shear_stress_pa", "values": [16.2], "unit": "kPa",
      "condition": {"normal_stress_pa": 24.0}},
     ["condition normal_stress_pa = 24 Pa is below the normal stresses of laboratory shear", "was it kPa"]),
    # a friction coefficient of 0.9 typed as a friction angle
    ({"test": "dst", "quantity": "friction_angle_deg", "values": [0.9], "unit": "deg"},
     ["0.9 deg is below the friction angles of granular materials", "was it a friction coefficient"]),
]


def test_each_slip_is_stored_with_a_warning_and_repeated_in_the_campaign_report(s2):
    client, app, settings = s2
    material = client.post(f"{API}/materials", json={"name": "slipped aggregate"})
    assert material.status_code == 201 and material.json()["measurements"] == []
    material_id = material.json()["id"]
    entry_warnings = []
    for measurement, words in SLIPS:
        added = client.post(f"{API}/materials/{material_id}/measurements", json=measurement)
        assert added.status_code == 201, added.text  # stored, not refused
        (warning,) = added.json()["warnings"]
        assert all(w in warning for w in words), warning
        assert warning.startswith(f"measurement {added.json()['id']} ")
        entry_warnings.append(warning)
    # a plausible second DST load (52.4 kPa, the thesis's): no warning, and the DST has its two stresses
    plain = client.post(f"{API}/materials/{material_id}/measurements", json={
        "test": "dst", "quantity": "residual_shear_stress_pa", "values": [40.0], "unit": "kPa",
        "condition": {"normal_stress_pa": 52.4}, "condition_units": {"normal_stress_pa": "kPa"}})
    assert plain.status_code == 201 and plain.json()["warnings"] == []
    # every listing repeats them
    listed = client.get(f"{API}/materials/{material_id}").json()["measurements"]
    assert [w for m in listed for w in m["warnings"]] == entry_warnings

    body = campaign_body(material_id, targets=None, diagnose=False)
    created = client.post(f"{API}/campaigns", json=body)
    assert created.status_code == 201, created.text
    cid = created.json()["id"]
    assert created.json()["warnings"] == []  # the thesis's factor ranges are plausible
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    report = client.get(f"{API}/campaigns/{cid}/report").json()
    assert report["warnings"] == entry_warnings
    stored = client.get(f"{API}/campaigns/{cid}/iterations").json()["items"][0]["report"]
    assert stored["warnings"] == entry_warnings


def test_a_g_per_cm3_value_entered_as_kg_per_m3_of_a_density_above_osmium_is_refused(s2):
    """Impossible, not implausible: 1,398 g/cm3 (a kg/m3 number with --unit g/cm3) is above osmium's 22,590 kg/m3."""
    client, _, _ = s2
    material_id = client.post(f"{API}/materials", json={"name": "dense"}).json()["id"]
    refused = client.post(f"{API}/materials/{material_id}/measurements", json={
        "test": "fill", "quantity": "bulk_density_kg_m3", "values": [1397.8], "unit": "g/cm3"})
    assert refused.status_code == 422 and refused.json()["detail"][0]["loc"] == ["body", "values", "0"]


def test_a_job_with_a_g_per_cm3_particle_density_is_queued_with_a_warning(s2):
    client, _, _ = s2
    job = client.post(f"{API}/jobs", json={"evaluator": "analytic", "parameters": {"particle_density_kg_m3": 2.6}})
    assert job.status_code == 201, job.text
    (warning,) = job.json()["warnings"]
    assert warning.startswith("parameters.particle_density_kg_m3 = 2.6 kg/m3 is below the solid densities of grains")
    assert "was it g/cm3" in warning
    assert client.get(f"{API}/jobs/{job.json()['id']}").json()["warnings"] == [warning]
    plain = client.post(f"{API}/jobs", json={"evaluator": "analytic"})
    assert plain.status_code == 201 and plain.json()["warnings"] == []


def test_a_campaign_with_a_stiffness_range_in_kn_per_m_is_created_with_warnings(s2):
    client, _, _ = s2
    material_id = next(m["id"] for m in client.get(f"{API}/materials").json()["items"] if m["bundled"])
    body = campaign_body(material_id, factors=[
        {"name": "particle_density_kg_m3", "low": 2300.0, "high": 2700.0},
        {"name": "particle_stiffness_n_per_m", "low": 1e3, "high": 3e3},
        {"name": "friction_pp", "low": 0.3, "high": 1.0}])
    created = client.post(f"{API}/campaigns", json=body)
    assert created.status_code == 201, created.text
    low, high = created.json()["warnings"]
    assert low.startswith("factors[1] particle_stiffness_n_per_m low = 1,000 N/m is below") and "was it kN/m" in low
    assert high.startswith("factors[1] particle_stiffness_n_per_m high = 3,000 N/m is below") and "was it kN/m" in high


def test_a_campaign_on_a_material_without_measurements_is_refused_naming_material_id(s2):
    client, _, _ = s2
    empty = client.post(f"{API}/materials", json={"name": "nothing measured yet"}).json()["id"]
    refused = client.post(f"{API}/campaigns", json=campaign_body(empty, targets=None))
    assert refused.status_code == 422, refused.text
    detail = refused.json()["detail"][0]
    assert detail["loc"] == ["body", "material_id"] and "has no measurements" in detail["msg"]
    assert client.get(f"{API}/campaigns").json()["items"] == []


def test_a_campaign_whose_targets_its_test_does_not_run_is_refused_naming_targets(s2):
    """The thesis aggregate has an angle of repose, but the battery runs the AOR only with include_aor."""
    client, _, _ = s2
    material_id = next(m["id"] for m in client.get(f"{API}/materials").json()["items"] if m["bundled"])
    aor = [{"test": "aor", "quantity": "angle_of_repose_deg"}]
    refused = client.post(f"{API}/campaigns", json=campaign_body(material_id, targets=aor))
    assert refused.status_code == 422, refused.text
    detail = refused.json()["detail"][0]
    assert detail["loc"] == ["body", "targets"] and "no target is simulated" in detail["msg"]
    assert "reports ['fill', 'cct', 'dst']" in detail["msg"] and "options.include_aor=true" in detail["msg"]
    accepted = client.post(f"{API}/campaigns", json=campaign_body(material_id, targets=aor,
                                                                  options={"include_aor": True}))
    assert accepted.status_code == 201, accepted.text
    # targets that are measurements of another material: none chosen, refused naming targets
    other = client.post(f"{API}/campaigns", json=campaign_body(material_id, targets=[
        {"test": "dst", "quantity": "residual_shear_stress_pa", "condition": {"normal_stress_pa": 1.0e5}}]))
    assert other.status_code == 422 and other.json()["detail"][0]["loc"] == ["body", "targets"]


def test_the_catalogue_serves_each_typical_range_with_its_source(s2):
    client, _, _ = s2
    quantities = {(t["name"], q["name"]): q for t in client.get(f"{API}/tests").json()["tests"] for q in t["quantities"]}
    modulus = quantities[("cct", "confined_modulus_pa")]["typical"]
    assert (modulus["low"], modulus["high"]) == (1.0e6, 1.0e9) and "Domenico" in modulus["source"]
    assert quantities[("fill", "bulk_mass_kg")]["typical"] is None  # the container sets it


def test_a_next_iteration_whose_targets_its_test_does_not_run_is_refused_and_nothing_changes(s2):
    """The same refusal when a completed campaign's next iteration changes its targets: the campaign stays
    completed with its configuration, rather than running a design whose targets it cannot compare."""
    client, app, settings = s2
    material_id = next(m["id"] for m in client.get(f"{API}/materials").json()["items"] if m["bundled"])
    cid = client.post(f"{API}/campaigns", json=campaign_body(material_id, diagnose=False, polish_steps=0)).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    before = client.get(f"{API}/campaigns/{cid}").json()
    refused = client.post(f"{API}/campaigns/{cid}/iterations",
                          json={"targets": [{"test": "aor", "quantity": "angle_of_repose_deg"}]})
    assert refused.status_code == 422 and refused.json()["detail"][0]["loc"] == ["body", "targets"], refused.text
    after = client.get(f"{API}/campaigns/{cid}").json()
    assert (after["status"], after["config"], after["current_iteration"]) == \
        ("completed", before["config"], before["current_iteration"])
