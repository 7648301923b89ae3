"""Issue 13, bad input: every case refused with a 422 naming its field, nothing stored, listings intact.

Each case is one the issue found accepted (or answered with a 500). After each refusal the test reads
the listing back: it answers 200 and holds exactly what it held before.
"""
from __future__ import annotations

import json

import pytest
from conftest_s2 import API, campaign_body, editable_thesis_copy, s2, thesis_material_id  # noqa: F401

SQLITE_INT_MAX = 2**63 - 1  # the largest integer SQLite and PostgreSQL BIGINT hold
ID_MAX = 2**31 - 1  # the largest PostgreSQL INTEGER


def locs(response) -> list[list]:
    return [err["loc"] for err in response.json()["detail"]]


def assert_refused(response, loc: list, status: int = 422) -> None:
    assert response.status_code == status, response.text
    assert loc in locs(response), locs(response)


def snapshot(client) -> dict:
    """Everything a listing shows; compared before and after each refusal."""
    materials = client.get(f"{API}/materials")
    jobs = client.get(f"{API}/jobs")
    campaigns = client.get(f"{API}/campaigns")
    schedules = client.get(f"{API}/schedules")
    for response in (materials, jobs, campaigns, schedules):
        assert response.status_code == 200, response.text
    return {"materials": materials.json(), "jobs": jobs.json(), "campaigns": campaigns.json(),
            "schedules": schedules.json()}


def post_raw(client, path: str, text: str):
    """A body as raw JSON text: Python's json module writes NaN/Infinity tokens, as the issue's client did."""
    return client.post(f"{API}{path}", content=text, headers={"Content-Type": "application/json"})


# -- measurements ------------------------------------------------------------------------------------

# (test, quantity, value, unit): each outside its quantity's physical range by definition.
OUT_OF_RANGE = [
    ("fill", "porosity", 1.7, None),  # a volume fraction is below 1
    ("fill", "porosity", 0.0, None),  # a packing of particles has voids
    ("dst", "friction_angle_deg", 400.0, None),  # a slope angle lies between flat and vertical
    ("dst", "friction_angle_deg", 90.0, None),
    ("aor", "angle_of_repose_deg", -5.0, None),
    ("fill", "bulk_density_kg_m3", -1400.0, None),  # densities are positive
    ("fill", "bulk_density_kg_m3", 1e308, None),  # denser than osmium (22,590 kg/m3)
    ("fill", "bulk_density_kg_m3", 23.0, "g/cm3"),  # the same ceiling after unit conversion
    ("cct", "confined_modulus_pa", 2e12, None),  # stiffer than diamond (~1.2e12 Pa)
    ("dst", "mohr_coulomb_r2", 1.5, None),  # a coefficient of determination is at most 1
    ("cct", "confined_modulus_pa", 1e300, "GPa"),  # finite as sent, infinite in SI
    ("fill", "porosity", 1e200, None),
]


@pytest.mark.parametrize("test, quantity, value, unit", OUT_OF_RANGE)
def test_measurement_outside_physical_bounds(s2, test, quantity, value, unit):
    client, _, _ = s2
    material_id = editable_thesis_copy(client)
    before = snapshot(client)
    body = {"test": test, "quantity": quantity, "values": [value]}
    if unit:
        body["unit"] = unit
    response = client.post(f"{API}/materials/{material_id}/measurements", json=body)
    assert_refused(response, ["body", "values", "0"])
    assert quantity in response.json()["detail"][0]["msg"]
    assert snapshot(client) == before


def test_huge_opposite_replicates_are_refused_and_listing_survives(s2):
    """values [1e200, -1e200] used to be stored (answering 500), then broke GET /materials for everyone."""
    client, _, _ = s2
    material_id = editable_thesis_copy(client)
    before = snapshot(client)
    response = client.post(f"{API}/materials/{material_id}/measurements", json={
        "test": "dst", "quantity": "residual_shear_stress_pa", "values": [1e200, -1e200],
        "condition": {"normal_stress_pa": 24000.0}})
    assert_refused(response, ["body", "values", "0"])
    assert snapshot(client) == before


@pytest.mark.parametrize("text, loc", [
    ('{"test": "fill", "quantity": "porosity", "values": [NaN]}', ["body", "values", 0]),
    ('{"test": "fill", "quantity": "porosity", "values": [Infinity]}', ["body", "values", 0]),
    ('{"test": "dst", "quantity": "residual_shear_stress_pa", "values": [17000.0], '
     '"condition": {"normal_stress_pa": NaN}}', ["body", "condition", "normal_stress_pa"]),
    ('{"test": "fill", "quantity": "porosity", "values": [0.45], "standard_uncertainty": Infinity}',
     ["body", "standard_uncertainty"]),
])
def test_non_finite_measurement_numbers(s2, text, loc):
    client, _, _ = s2
    material_id = editable_thesis_copy(client)
    before = snapshot(client)
    assert_refused(post_raw(client, f"/materials/{material_id}/measurements", text), loc)
    assert snapshot(client) == before


def test_non_finite_direct_estimate_is_refused(s2):
    """NaN in direct_estimates used to be stored as null."""
    client, _, _ = s2
    before = snapshot(client)
    text = json.dumps({"name": "nan estimate", "direct_estimates": {"particle_density_kg_m3": {"value": float("nan")}}})
    assert "NaN" in text
    response = post_raw(client, "/materials", text)
    assert_refused(response, ["body", "direct_estimates"])
    assert "particle_density_kg_m3.value" in response.json()["detail"][0]["msg"]
    assert snapshot(client) == before


def test_too_many_replicates(s2):
    client, _, _ = s2
    material_id = editable_thesis_copy(client)
    before = snapshot(client)
    response = client.post(f"{API}/materials/{material_id}/measurements",
                           json={"test": "fill", "quantity": "porosity", "values": [0.45] * 100_000})
    assert_refused(response, ["body", "values"])
    assert snapshot(client) == before


def test_duplicate_measurement_is_refused_not_dropped(s2):
    """One (test, quantity, condition) holds one measurement: a second is refused, naming the first."""
    client, _, _ = s2
    material_id = editable_thesis_copy(client)
    existing = next(m for m in client.get(f"{API}/materials/{material_id}").json()["measurements"]
                    if (m["test"], m["quantity"]) == ("dst", "friction_angle_deg"))
    before = snapshot(client)
    response = client.post(f"{API}/materials/{material_id}/measurements",
                           json={"test": "dst", "quantity": "friction_angle_deg", "values": [59.8, 61.0]})
    assert_refused(response, ["body", "condition"])
    assert f"measurement {existing['id']}" in response.json()["detail"][0]["msg"]
    assert snapshot(client) == before
    # the same quantity at another condition is a different measurement; in kPa, it is the same condition
    at_24 = {"test": "dst", "quantity": "residual_shear_stress_pa", "values": [17.0], "unit": "kPa",
             "condition": {"normal_stress_pa": 24000.0}}
    assert client.post(f"{API}/materials/{material_id}/measurements", json=at_24).status_code == 201
    same_in_kpa = dict(at_24, condition={"normal_stress_pa": 24.0}, condition_units={"normal_stress_pa": "kPa"})
    assert_refused(client.post(f"{API}/materials/{material_id}/measurements", json=same_in_kpa),
                   ["body", "condition"])


def test_duplicates_within_one_new_material(s2):
    client, _, _ = s2
    before = snapshot(client)
    porosity = {"test": "fill", "quantity": "porosity", "values": [0.45]}
    response = client.post(f"{API}/materials", json={"name": "dup", "measurements": [porosity, porosity]})
    assert_refused(response, ["body", "measurements", "1", "condition"])
    assert snapshot(client) == before  # neither the material nor its first measurement was stored


def test_legacy_non_finite_row_does_not_break_listings(s2):
    """A row stored before validation existed (inf, NaN) is shown with nulls; the listing answers 200."""
    from service.models.material import Measurement

    client, app, _ = s2
    material_id = client.post(f"{API}/materials", json={"name": "legacy"}).json()["id"]
    with app.state.session_factory() as session:
        session.add(Measurement(material_id=material_id, test="fill", quantity="bulk_mass_kg", condition={},
                                unit="kg", values=[1e308, 1e308], input_unit="kg"))
        session.add(Measurement(material_id=material_id, test="cct", quantity="bulk_stiffness_n_per_m",
                                condition={}, unit="N/m", values=[float("inf")], input_unit="N/m"))
        session.commit()
    listing = client.get(f"{API}/materials")
    assert listing.status_code == 200
    rows = next(m for m in listing.json()["items"] if m["id"] == material_id)["measurements"]
    mass = next(r for r in rows if r["quantity"] == "bulk_mass_kg")
    assert mass["mean"] is None and mass["values"] == [1e308, 1e308]  # the sum overflows; the values are kept
    stiffness = next(r for r in rows if r["quantity"] == "bulk_stiffness_n_per_m")
    assert stiffness["values"] == [None]
    assert client.get(f"{API}/materials/{material_id}/measurements").status_code == 200


# -- integers the database cannot hold -------------------------------------------------------------
# Ids are INTEGER columns, 32-bit on PostgreSQL (2^31 - 1 is the largest; an id past it answered 500 there);
# offsets are bigints on both stores.

@pytest.mark.postgres
@pytest.mark.parametrize("path, loc", [
    (f"/jobs/{ID_MAX + 1}", ["path", "job_id"]),
    (f"/jobs/{2**70}/result", ["path", "job_id"]),
    (f"/materials/{ID_MAX + 1}", ["path", "material_id"]),
    (f"/materials/1/measurements/{ID_MAX + 1}", ["path", "measurement_id"]),
    (f"/campaigns/{ID_MAX + 1}", ["path", "campaign_id"]),
    (f"/campaigns/1/iterations/{ID_MAX + 1}", ["path", "number"]),
    (f"/campaigns/1/report?number={ID_MAX + 1}", ["query", "number"]),
    (f"/schedules/{ID_MAX + 1}", ["path", "schedule_id"]),
    (f"/jobs?offset={SQLITE_INT_MAX + 1}", ["query", "offset"]),
    (f"/jobs?campaign_id={ID_MAX + 1}", ["query", "campaign_id"]),
])
def test_ids_and_offsets_beyond_the_database_integers(s2, path, loc):
    client, _, _ = s2
    before = snapshot(client)
    method = client.delete if "measurements/" in path else client.get
    assert_refused(method(f"{API}{path}"), loc)
    assert snapshot(client) == before  # the same connection still answers


@pytest.mark.postgres
def test_largest_id_and_offset_are_a_plain_404_and_an_empty_page(s2):
    client, _, _ = s2
    assert client.get(f"{API}/jobs/{ID_MAX}").status_code == 404
    assert client.get(f"{API}/campaigns/{ID_MAX}").status_code == 404
    assert client.get(f"{API}/jobs?campaign_id={ID_MAX}").json()["items"] == []
    assert client.get(f"{API}/jobs?offset={SQLITE_INT_MAX}").json()["items"] == []


# -- NUL characters: PostgreSQL's text cannot hold them (a name or key holding one answered 500 there) --

NUL_BODIES = [
    ("/materials", {"name": "gravel\u0000"}, ["body", "name"]),
    ("/materials", {"name": "gravel", "source": "lab\u0000book"}, ["body", "source"]),
    ("/materials", {"name": "gravel", "direct_estimates": {"k\u0000ey": 1.0}}, ["body", "direct_estimates", "key"]),
    ("/jobs", {"evaluator": "analytic", "idempotency_key": "k\u0000"}, ["body", "idempotency_key"]),
]


@pytest.mark.postgres
@pytest.mark.parametrize("path, body, loc", NUL_BODIES)
def test_nul_in_a_body_string_is_refused_on_both_stores(s2, path, body, loc):
    client, _, _ = s2
    before = snapshot(client)
    text = json.dumps(body)
    assert "\\u0000" in text  # JSON's escape for U+0000
    assert_refused(post_raw(client, path, text), loc)
    assert snapshot(client) == before


@pytest.mark.postgres
@pytest.mark.parametrize("path, loc", [
    ("/schedules/cron-preview?expr=0%002%20*%20*%20*", ["query", "expr"]),
    ("/materials?name%00=1", ["query", "name"]),
    ("/jobs/1/curves/shear%00", ["path"]),
])
def test_nul_in_the_query_or_path_is_refused_on_both_stores(s2, path, loc):
    client, _, _ = s2
    assert_refused(client.get(f"{API}{path}"), loc)
    assert snapshot(client)  # the server still answers


def test_an_escaped_backslash_before_u0000_is_no_nul(s2):
    """``\\\\u0000`` in JSON is a backslash and the text "u0000": a path on Windows, say, not a NUL."""
    client, _, _ = s2
    response = post_raw(client, "/materials", json.dumps({"name": "C:\\u0000 gravel"}))
    assert response.status_code == 201, response.text
    assert response.json()["name"] == "C:\\u0000 gravel"


@pytest.mark.parametrize("body, loc", [
    ({"seed": 2**63}, ["body", "seed"]),
    ({"seed": 2**32}, ["body", "seed"]),  # seeds are 32-bit
    ({"priority": 2**63}, ["body", "priority"]),
    ({"campaign_id": 2**63}, ["body", "campaign_id"]),
])
def test_job_integers_out_of_range(s2, body, loc):
    client, _, _ = s2
    before = snapshot(client)
    assert_refused(client.post(f"{API}/jobs", json={"evaluator": "analytic", **body}), loc)
    assert snapshot(client) == before


def test_campaign_priority_beyond_range(s2):
    """priority 2**70 used to be accepted and fail on start with an internal error."""
    client, _, _ = s2
    before = snapshot(client)
    response = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), priority=2**70))
    assert_refused(response, ["body", "priority"])
    assert snapshot(client) == before


@pytest.mark.parametrize("seeds", [0, 9, "two"])
def test_campaign_confirmation_seeds_out_of_range(s2, seeds):
    """No battery at the optimum (0) leaves nothing to compare; more than 8 is refused as a typo."""
    client, _, _ = s2
    before = snapshot(client)
    response = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), confirmation_seeds=seeds))
    assert_refused(response, ["body", "confirmation_seeds"])
    assert snapshot(client) == before


# -- job specs ------------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, loc", [
    ('{"evaluator": "analytic", "parameters": {"particle_density_kg_m3": Infinity}}',
     ["body", "parameters", "particle_density_kg_m3"]),
    ('{"evaluator": "analytic", "parameters": {"particle_density_kg_m3": "inf"}}',
     ["body", "parameters", "particle_density_kg_m3"]),
    ('{"evaluator": "analytic", "parameters": {"friction_pp": NaN}}', ["body", "parameters", "friction_pp"]),
    ('{"evaluator": "analytic", "options": {"cct_max_stress_pa": -Infinity}}', ["body", "options", "cct_max_stress_pa"]),
])
def test_non_finite_job_numbers(s2, text, loc):
    client, _, _ = s2
    before = snapshot(client)
    assert_refused(post_raw(client, "/jobs", text), loc)
    assert snapshot(client) == before


@pytest.mark.parametrize("parameters, loc", [
    ({"particle_radius_m": 1e200}, ["body", "parameters", "particle_radius_m"]),  # overflowed the estimate
    ({"particle_radius_m": 1e-200}, ["body", "parameters", "particle_radius_m"]),  # divided by zero
    ({"particle_density_kg_m3": 1e308}, ["body", "parameters", "particle_density_kg_m3"]),
    ({"particle_density_kg_m3": 23_000.0}, ["body", "parameters", "particle_density_kg_m3"]),  # > osmium
    ({"friction_pp": 1e6}, ["body", "parameters", "friction_pp"]),
    ({"particle_stiffness_n_per_m": 1e13}, ["body", "parameters", "particle_stiffness_n_per_m"]),
    ({"effects": {"rolling_resistance": {"rolling_friction": 0.1}}}, ["body", "parameters", "effects"]),
    ({"effects": {"rolling_epsd2": {"rolling_friction": "abc"}}}, ["body", "parameters", "effects"]),
    ({"effects": {"rolling_epsd2": {}}}, ["body", "parameters", "effects"]),
    ({"effects": {"rolling_epsd2": {"rolling_friction": 0.1, "typo": 1}}}, ["body", "parameters", "effects"]),
])
def test_job_parameters_out_of_range(s2, parameters, loc):
    client, _, _ = s2
    before = snapshot(client)
    response = client.post(f"{API}/jobs", json={"evaluator": "dem", "parameters": parameters})
    assert_refused(response, loc)
    if "effects" in parameters:
        name = next(iter(parameters["effects"]))
        assert name in response.json()["detail"][0]["msg"]
    assert snapshot(client) == before


def test_registered_effect_is_accepted(s2):
    client, _, _ = s2
    response = client.post(f"{API}/jobs", json={"evaluator": "analytic",
                                                "parameters": {"effects": {"rolling_epsd2": {"rolling_friction": 0.1}}}})
    assert response.status_code == 201, response.text


@pytest.mark.parametrize("stresses", [[24000.0], [24000.0, 24000.0], [24000.0, -10.0]])
def test_shear_test_needs_two_distinct_stress_levels(s2, stresses):
    """One level (or two equal) fits a Mohr-Coulomb line exactly or not at all: no friction angle."""
    client, _, _ = s2
    before = snapshot(client)
    response = client.post(f"{API}/jobs", json={"evaluator": "analytic", "test": "dst",
                                                "options": {"dst_normal_stresses_pa": stresses}})
    assert_refused(response, ["body", "options", "dst_normal_stresses_pa"])
    assert snapshot(client) == before


# -- campaigns, iterations, schedules: the same rules at every entry point ---------------------------

BAD_EFFECT = {"effects": {"rolling_resistance": {"rolling_friction": 0.1}}}


def test_campaign_refuses_unknown_effect_and_nan_target_condition(s2):
    client, _, _ = s2
    material_id = thesis_material_id(client)
    before = snapshot(client)
    assert_refused(client.post(f"{API}/campaigns", json=campaign_body(material_id, fixed_parameters=BAD_EFFECT)),
                   ["body", "fixed_parameters", "effects"])
    text = json.dumps(campaign_body(material_id, targets=[
        {"test": "dst", "quantity": "residual_shear_stress_pa", "condition": {"normal_stress_pa": float("nan")}}]))
    assert_refused(post_raw(client, "/campaigns", text), ["body", "targets", 0, "condition", "normal_stress_pa"])
    assert snapshot(client) == before


def test_schedule_template_refuses_unknown_effect(s2):
    client, _, _ = s2
    before = snapshot(client)
    body = {"name": "nightly", "cron": "0 2 * * *",
            "template": campaign_body(thesis_material_id(client), fixed_parameters=BAD_EFFECT)}
    assert_refused(client.post(f"{API}/schedules", json=body), ["body", "template", "fixed_parameters", "effects"])
    assert snapshot(client) == before


def test_iteration_refuses_unknown_effect_before_looking_at_state(s2):
    client, _, _ = s2
    campaign = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()
    before = snapshot(client)
    response = client.post(f"{API}/campaigns/{campaign['id']}/iterations", json={"fixed_parameters": BAD_EFFECT})
    # a 422 naming the effect, though the draft could not iterate anyway (409)
    assert_refused(response, ["body", "fixed_parameters", "effects"])
    assert snapshot(client) == before
