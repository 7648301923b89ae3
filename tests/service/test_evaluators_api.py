"""GET /api/v1/evaluators serves the registry, and every evaluator field, filter and choice follows
it: a backend registered once is listed, accepted, queued and run by a worker; an unknown name is a
422 naming the field."""
from __future__ import annotations

import pytest

from calibration.evaluator_registry import names
from service.cli import build_parser
from service.workers.local import Worker

API = "/api/v1"


def _detail(response) -> list[tuple[list, str]]:
    assert response.status_code == 422, response.text
    return [(err["loc"], err["msg"]) for err in response.json()["detail"]]


def test_the_catalogue_is_the_registry(client):
    body = client.get(f"{API}/evaluators").json()
    assert [e["name"] for e in body["evaluators"]] == names() == ["dem", "analytic"]
    dem = body["evaluators"][0]
    assert dem["title"] == "simulation" and "numba" in dem["description"]
    assert set(dem["tests"]) == {"battery", "fill", "cct", "dst", "aor", "anchor"}
    openapi = client.get(f"{API}/openapi.json").json()
    response = openapi["paths"][f"{API}/evaluators"]["get"]["responses"]["200"]["content"]["application/json"]
    assert response["schema"]["$ref"].endswith("/EvaluatorCatalogue")
    submit = openapi["components"]["schemas"]["JobSubmit"]["properties"]["evaluator"]
    assert submit["enum"] == ["dem", "analytic"] and submit["default"] == "dem"


@pytest.mark.parametrize("method, path, kwargs, loc", [
    ("post", "/jobs", {"json": {"evaluator": "python"}}, ["body", "evaluator"]),
    ("get", "/jobs", {"params": {"evaluator": "python"}}, ["query", "evaluator"]),
])
def test_an_unknown_evaluator_is_a_422_naming_the_field_and_the_choices(client, method, path, kwargs, loc):
    ((got_loc, msg),) = _detail(getattr(client, method)(f"{API}{path}", **kwargs))
    assert got_loc == loc and "unknown evaluator 'python'; choose one of ['dem', 'analytic']" in msg


def test_a_registered_backend_is_listed_accepted_and_run_by_a_worker(client, shear_only):
    assert "shear-only" in [e["name"] for e in client.get(f"{API}/evaluators").json()["evaluators"]]
    job = client.post(f"{API}/jobs", json={"evaluator": "shear-only", "test": "dst", "seed": 4})
    assert job.status_code == 201, job.text
    app = client.app
    assert Worker(app.state.session_factory, app.state.settings, "registry-test").run_one() == "succeeded"
    listed = client.get(f"{API}/jobs", params={"evaluator": "shear-only"}).json()["items"]
    assert [j["id"] for j in listed] == [job.json()["id"]] and listed[0]["status"] == "succeeded"
    result = client.get(f"{API}/jobs/{job.json()['id']}/result").json()
    assert {p["test"] for p in result["properties"]} == {"dst"}


def test_a_test_the_backend_does_not_run_is_refused_at_submission(client, shear_only):
    ((loc, msg),) = _detail(client.post(f"{API}/jobs", json={"evaluator": "shear-only", "test": "cct"}))
    assert loc == ["body", "test"] and "'shear-only' does not run test 'cct'" in msg


def test_the_cli_offers_the_registered_names():
    parser = build_parser()
    for argv in (["job", "submit", "--evaluator", "analytic"], ["campaign", "create", "--evaluator", "dem"]):
        assert parser.parse_args(argv).evaluator == argv[-1]
    with pytest.raises(SystemExit):
        parser.parse_args(["job", "submit", "--evaluator", "python"])
