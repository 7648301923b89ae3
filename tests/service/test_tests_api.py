"""GET /api/v1/tests, the CLI's choices, the schemas and the page all read the lab-test registry (issue 28)."""
from __future__ import annotations

import re
from pathlib import Path

from conftest_s2 import API, campaign_body, error_loc, s2, thesis_material_id  # noqa: F401

from engine.lab import registry
from engine.lab.units import accepted_units

STATIC_JS = Path(__file__).resolve().parents[2] / "service" / "web" / "static" / "js"


def test_catalogue_is_the_registry(s2):
    client, _, _ = s2
    body = client.get(f"{API}/tests").json()
    assert body["job_tests"] == registry.job_test_names()
    assert [t["name"] for t in body["tests"]] == list(registry.tests())
    for served in body["tests"]:
        declared = registry.get(served["name"])
        assert served["needs"] == list(declared.needs) and served["options"] == list(declared.options)
        assert [q["name"] for q in served["quantities"]] == [q.name for q in declared.quantities]
        for q in served["quantities"]:
            bound = declared.quantity(q["name"]).bound
            assert q["si_unit"] == declared.quantity(q["name"]).unit and q["si_unit"] in q["accepted_units"]
            assert q["bounds"]["low_inclusive"] == (not bound.low_open)
            assert q["bounds"]["high"] == (None if bound.high == float("inf") else bound.high)
    always = [n for n, t in registry.tests().items() if t.battery == registry.ALWAYS]
    assert body["battery"] == {"name": "battery", "always": always,
                               "optional": {"aor": "include_aor", "anchor": "include_anchor"}}


def test_every_unit_is_one_a_measurement_can_be_sent_in():
    """A declared SI unit the unit table does not know would take no input unit but itself."""
    for test in registry.tests().values():
        for q in test.quantities:
            assert len(accepted_units(q.unit)) > 1, (test.name, q.name)


def test_materials_quantities_are_the_catalogues(s2):
    client, _, _ = s2
    catalogue = client.get(f"{API}/tests").json()
    quantities = client.get(f"{API}/materials/quantities").json()
    assert quantities == {t["name"]: {q["name"]: {k: q[k] for k in ("si_unit", "accepted_units", "bounds")}
                                      for q in t["quantities"]} for t in catalogue["tests"]}


def test_openapi_documents_the_registrys_names_on_jobs_and_campaigns(s2):
    client, _, _ = s2
    schemas = client.get(f"{API}/openapi.json").json()["components"]["schemas"]
    for model in ("JobSubmit", "CampaignCreate"):
        assert schemas[model]["properties"]["test"]["enum"] == registry.job_test_names(), model
    assert "TestCatalogue" in schemas


def test_an_unknown_test_is_a_422_naming_the_field(s2):
    client, _, _ = s2
    r = client.post(f"{API}/jobs", json={"evaluator": "analytic", "test": "shear"})
    assert r.status_code == 422 and error_loc(r) == ["body", "test"] and "battery" in r.json()["detail"][0]["msg"]
    r = client.get(f"{API}/jobs", params={"test": "shear"})
    assert r.status_code == 422 and error_loc(r) == ["query", "test"]
    r = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), test="shear"))
    assert r.status_code == 422 and error_loc(r) == ["body", "test"]
    assert client.post(f"{API}/jobs", json={"evaluator": "analytic", "test": "aor"}).status_code == 201


def test_cli_choices_are_the_registrys_names():
    from service.cli import build_parser

    parser = build_parser()
    job = parser._subparsers._group_actions[0].choices["job"]
    job_commands = job._subparsers._group_actions[0].choices
    for command in ("submit", "list"):
        (test,) = [a for a in job_commands[command]._actions if a.dest == "test"]
        assert list(test.choices) == registry.job_test_names(), command


def test_the_page_lists_no_test_names_of_its_own():
    """The selects and battery switches come from GET /tests (labtests.js), not from lists in the page."""
    names = "|".join(registry.tests())
    for path in STATIC_JS.glob("*.js"):
        text = path.read_text()
        assert not re.search(rf'\[\s*"battery"\s*,\s*"({names})"', text), path.name
        assert "include_aor" not in text and "include_anchor" not in text, path.name
