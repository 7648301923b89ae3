"""Issue 32, items 1 and 4: nothing one request sends can break the service for the others, and hygiene.

Each test is a defect the issue found: a deeply nested material stored and then breaking every listing, a
100 MiB body read in full, a 40 MB prior source accepted, a 1,000-term constraint answered 500, a job's
stale error kept after success, one-character and shared tokens accepted, 422 instead of 405 on fixed
paths, ``false`` taken as 0.0.
"""
from __future__ import annotations

import asyncio
import json
import time

import pytest
from fastapi.testclient import TestClient

from conftest_s2 import API, campaign_body, running_app, s2, s2_settings, thesis_material_id  # noqa: F401
from engine.lab.spec import JobSpec
from service import queue
from service.app import create_app

MiB = 1024 * 1024
LOCAL = "http://127.0.0.1"  # a loopback Host, which a Host allow-list admits


def locs(response) -> list[list]:
    return [err["loc"] for err in response.json()["detail"]]


def nested(levels: int):
    value: object = 1.0
    for _ in range(levels):
        value = {"a": value}
    return value


# -- nesting depth -----------------------------------------------------------------------------------

def test_deeply_nested_material_is_refused_and_the_listing_stays_readable(client):
    """The body {"direct_estimates": {"x": <300 levels>}} was stored, answered 500, then broke GET /materials."""
    before = client.get(f"{API}/materials")
    assert before.status_code == 200
    r = client.post(f"{API}/materials", json={"name": "deep", "direct_estimates": {"x": nested(300)}})
    assert r.status_code == 422 and locs(r) == [["body", "direct_estimates"]], r.text
    after = client.get(f"{API}/materials")
    assert after.status_code == 200 and after.json() == before.json()


def test_depth_limit_is_the_setting(client, settings):
    """The body is level 1, direct_estimates 2, so ``max_json_depth - 2`` levels inside fit exactly."""
    inside = settings.max_json_depth - 2
    ok = client.post(f"{API}/materials", json={"name": "at the limit", "direct_estimates": {"x": nested(inside)}})
    assert ok.status_code == 201, ok.text
    over = client.post(f"{API}/materials", json={"name": "over", "direct_estimates": {"x": nested(inside + 1)}})
    assert over.status_code == 422 and locs(over) == [["body", "direct_estimates"]]
    assert [m["name"] for m in client.get(f"{API}/materials").json()["items"]] == ["at the limit"]


def test_depth_scan_ignores_brackets_in_strings():
    from service.bounds import json_depth

    text = json.dumps({"name": "[[[[{{{{" * 100, "direct_estimates": {"x": {"y": 1}}}).encode()
    assert json_depth(text, 3) == (0, None)
    assert json_depth(text, 2) == (3, "direct_estimates")
    assert json_depth(b"[[[1]]]", 2) == (3, None)


def fails_once(view):
    """``view`` (a row's API view), raising the first time as the serialiser did on a deep dict."""
    calls = []

    def failing(row):
        calls.append(row)
        if len(calls) == 1:
            raise RecursionError("maximum recursion depth exceeded while serialising")
        return view(row)

    return failing


def test_a_write_whose_response_cannot_be_built_leaves_no_row(settings, monkeypatch):
    """The create committed, then building the response raised: the client got a 500 and the row stayed.
    The response is now built before the commit, so the failure rolls the write back."""
    from service.api import materials as api

    monkeypatch.setattr(api, "material_dict", fails_once(api.material_dict))
    with TestClient(create_app(settings), base_url=LOCAL, raise_server_exceptions=False) as client:
        r = client.post(f"{API}/materials", json={"name": "unlucky"})
        assert r.status_code == 500
        listing = client.get(f"{API}/materials")
        assert listing.status_code == 200 and listing.json()["items"] == []


# -- body size ---------------------------------------------------------------------------------------

def _post_asgi(app, headers: list[tuple[bytes, bytes]], chunk: bytes, chunks: int) -> tuple[int, int]:
    """POST to the ASGI app with a body streamed as ``chunks`` pieces; (status, pieces the app read)."""
    read = 0
    sent: list[dict] = []

    async def receive():
        nonlocal read
        if read >= chunks:
            return {"type": "http.disconnect"}
        read += 1
        return {"type": "http.request", "body": chunk, "more_body": read < chunks}

    async def send(message):
        sent.append(message)

    scope = {"type": "http", "asgi": {"version": "3.0"}, "http_version": "1.1", "method": "POST", "scheme": "http",
             "path": f"{API}/materials", "raw_path": f"{API}/materials".encode(), "query_string": b"",
             "root_path": "", "headers": [(b"host", b"127.0.0.1"), (b"content-type", b"application/json"), *headers],
             "client": ("127.0.0.1", 5000), "server": ("127.0.0.1", 8000)}
    asyncio.run(app(scope, receive, send))
    return next(m["status"] for m in sent if m["type"] == "http.response.start"), read


def test_100_mib_body_is_refused_on_its_content_length_before_a_byte_is_read(settings):
    app = create_app(settings)
    status, read = _post_asgi(app, [(b"content-length", str(100 * MiB).encode())], b" " * 65536, 100 * 16)
    assert status == 413 and read == 0


def test_chunked_body_over_the_cap_is_refused_while_it_streams(settings):
    app = create_app(settings.model_copy(update={"max_body_bytes": MiB}))
    status, read = _post_asgi(app, [(b"transfer-encoding", b"chunked")], b" " * 65536, 100 * 16)  # 100 MiB
    assert status == 413 and read == MiB // 65536 + 1  # stopped at the first piece over 1 MiB


def test_body_over_the_cap_is_413_through_http(settings):
    with TestClient(create_app(settings.model_copy(update={"max_body_bytes": 4096})), base_url=LOCAL) as client:
        r = client.post(f"{API}/materials", json={"name": "big", "description": "x" * 5000})
        assert r.status_code == 413 and locs(r) == [["body"]] and "DEMCAL_MAX_BODY_BYTES" in r.text
        assert client.get(f"{API}/materials").json()["items"] == []


# -- free text and constraints -----------------------------------------------------------------------

def _prior(source: str) -> list[dict]:
    return [{"parameter": "friction_pp", "value": 0.6, "uncertainty": 0.1, "source": source}]


def test_40_mb_prior_source_is_refused(tmp_path):
    """Accepted before: every GET /campaigns then answered 42 MB."""
    roomy = s2_settings(tmp_path).model_copy(update={"max_body_bytes": 64 * MiB})  # so the field limit decides
    with running_app(roomy) as (client, _app):
        body = campaign_body(thesis_material_id(client), priors=_prior("x" * 40_000_000))
        r = client.post(f"{API}/campaigns", json=body)
        assert r.status_code == 422 and ["body", "priors", 0, "source"] in locs(r)
        assert client.get(f"{API}/campaigns").json()["items"] == []
        ok = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), priors=_prior("Table 4.2")))
        assert ok.status_code == 201, ok.text


def test_40_mb_body_is_refused_at_the_default_cap(s2):
    client, _app, _settings = s2
    r = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), priors=_prior("x" * 40_000_000)))
    assert r.status_code == 413


@pytest.mark.parametrize("terms, loc", [(1000, ["body", "constraints", 0]), (300, ["body", "constraints", 0])])
def test_long_constraint_is_refused_naming_it(s2, terms, loc):
    """1,000 terms exhausted the parser's recursion (500); 300 short ones fit in the characters but not the terms."""
    client, _app, _settings = s2
    text = " + ".join(["friction_pp"] * terms) + " <= 1000" if terms == 1000 else "+".join(["1"] * terms) + \
        " + friction_pp <= 1000"
    r = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client), constraints=[text]))
    assert r.status_code == 422 and loc in locs(r), r.text
    assert client.get(f"{API}/campaigns").json()["items"] == []


# -- hygiene -----------------------------------------------------------------------------------------

def test_stale_error_is_cleared_when_a_later_attempt_succeeds(session_factory):
    from calibration.evaluator_registry import run_job

    with session_factory() as s:
        job_id = queue.submit_job(s, JobSpec(), evaluator="analytic").id
        queue.claim_next(s, "dies", 0.05)
        time.sleep(0.1)
        assert queue.claim_next(s, "lives", 30).id == job_id  # the lost lease re-queued it with a reason
        assert queue.get_job(s, job_id).error
        assert queue.complete_job(s, job_id, "lives", run_job("analytic", JobSpec()), 1.0)
        job = queue.get_job(s, job_id)
    assert job.status == "succeeded" and job.error is None and job.attempts == 2


@pytest.mark.parametrize("update, needle", [
    ({"token": "t"}, "at least 16"),
    ({"token": "                    "}, "at least 16"),  # whitespace only
    ({"tokens": "alice:short"}, "'alice'"),
    ({"tokens": "alice:shared-token-0123456789,bob:shared-token-0123456789"}, "same token"),
    ({"token": "shared-token-0123456789", "tokens": "bob:shared-token-0123456789"}, "same token"),
    # "token:<name>" is the client identity, stored in 100-character columns (PostgreSQL enforces the width)
    ({"tokens": "n" * 95 + ":long-enough-token-0123"}, "at most 94"),
])
def test_short_or_shared_tokens_are_refused_at_start(settings, update, needle):
    with pytest.raises(SystemExit, match=needle) as refused:
        create_app(settings.model_copy(update=update))
    assert "\n" not in str(refused.value)


def test_one_user_may_hold_two_tokens(settings):
    create_app(settings.model_copy(update={"tokens": "alice:first-token-0123456789,alice:second-token-012345678"}))


@pytest.mark.parametrize("path", ["/materials/quantities", "/schedules/cron-preview"])
@pytest.mark.parametrize("method", ["POST", "PUT", "PATCH", "DELETE"])
def test_fixed_paths_answer_405_with_their_own_methods(client, path, method):
    r = client.request(method, f"{API}{path}")
    assert r.status_code == 405 and r.headers["allow"] == "GET", (r.status_code, r.headers.get("allow"))


@pytest.mark.parametrize("body, loc", [
    ({"evaluator": "analytic", "parameters": {"friction_pp": False}}, ["body", "parameters", "friction_pp"]),
    ({"evaluator": "analytic", "seed": True}, ["body", "seed"]),
    ({"evaluator": "analytic", "options": {"residual_window_strain": [False, 0.1]}},
     ["body", "options", "residual_window_strain", 0]),
])
def test_a_boolean_is_not_a_number(client, body, loc):
    r = client.post(f"{API}/jobs", json=body)
    assert r.status_code == 422 and loc in locs(r), r.text
    assert client.get(f"{API}/jobs").json()["total"] == 0


def test_a_number_is_not_a_boolean_and_json_numbers_still_fit(s2):
    client, _app, _settings = s2
    material = thesis_material_id(client)
    r = client.post(f"{API}/campaigns", json=campaign_body(material, allow_extrapolation=0))
    assert r.status_code == 422 and ["body", "allow_extrapolation"] in locs(r)
    r = client.post(f"{API}/materials/{material}/copy", json={"name": "c"})
    copy = r.json()["id"]
    r = client.post(f"{API}/materials/{copy}/measurements",
                    json={"test": "fill", "quantity": "porosity", "values": [False]})
    assert r.status_code == 422 and ["body", "values", 0] in locs(r)
    # integers where numbers are expected, and a list for a pair, are what a browser's JSON sends: accepted
    ok = client.post(f"{API}/campaigns", json=campaign_body(material, factors=[
        {"name": "particle_density_kg_m3", "low": 2300, "high": 2700, "unit": "kg/m3"},
        {"name": "particle_stiffness_n_per_m", "low": 1000000, "high": 3000000, "unit": "N/m"},
        {"name": "friction_pp", "low": 0.3, "high": 1}], options={"residual_window_strain": [0.08, 0.1]}))
    assert ok.status_code == 201, ok.text



def test_a_whole_float_is_an_integer_and_a_fraction_is_not(s2):
    """JSON Schema's "integer" admits 2.0 (one JSON number type), what a client computing a seed in floating
    point sends; strict models refused it while the published schema allowed it. 2.5 and true still fail."""
    client, _app, _settings = s2
    job = client.post(f"{API}/jobs", json={"evaluator": "analytic", "seed": 7.0, "priority": 2.0})
    assert job.status_code == 201, job.text
    assert (job.json()["spec"]["seed"], job.json()["priority"]) == (7, 2)
    for bad in (7.5, True, "7"):
        r = client.post(f"{API}/jobs", json={"evaluator": "analytic", "seed": bad})
        assert r.status_code == 422 and ["body", "seed"] in locs(r), (bad, r.text)
    material = thesis_material_id(client)
    design = {"type": "full", "centre_runs": 2.0}
    ok = client.post(f"{API}/campaigns", json=campaign_body(material, seed=3.0, design=design))
    assert ok.status_code == 201 and ok.json()["config"]["seed"] == 3, ok.text
    assert ok.json()["config"]["design"]["centre_runs"] == 2
    bad = client.post(f"{API}/campaigns", json=campaign_body(material, design={**design, "centre_runs": 2.5}))
    assert bad.status_code == 422 and ["body", "design", "centre_runs"] in locs(bad), bad.text

def test_health_is_503_when_a_row_cannot_be_read(client):
    """Corrupted row contents: SELECT 1 answered, health said ok, /jobs answered 500."""
    from sqlalchemy import text

    job = client.post(f"{API}/jobs", json={"evaluator": "analytic"}).json()
    assert client.get(f"{API}/health").status_code == 200
    with client.app.state.engine.begin() as connection:
        connection.execute(text("UPDATE jobs SET spec = '{not json' WHERE id = :id"), {"id": job["id"]})
    r = client.get(f"{API}/health")
    assert r.status_code == 503 and r.json()["status"] == "error"
    assert r.json()["database"] == f"unreadable: jobs row {job['id']}: JSONDecodeError"


def _unbounded(schemas: dict, schema: dict, where: str, seen: set) -> list[str]:
    """Strings without maxLength, arrays without maxItems, maps without maxProperties under ``schema``."""
    if "$ref" in schema:
        name = schema["$ref"].rsplit("/", 1)[-1]
        if name in seen:
            return []
        seen.add(name)
        return _unbounded(schemas, schemas[name], name, seen)
    found = [f for key in ("anyOf", "oneOf", "allOf") for s in schema.get(key, ()) for f in _unbounded(schemas, s, where, seen)]
    kind = schema.get("type")
    if kind == "string" and not {"maxLength", "enum", "const"} & set(schema):
        found.append(where)
    if kind == "array":
        found += [] if "maxItems" in schema else [where]
        for item in [schema.get("items", {}), *schema.get("prefixItems", ())]:
            found += _unbounded(schemas, item, f"{where}[]", seen)
    if kind == "object":
        for name, sub in schema.get("properties", {}).items():
            found += _unbounded(schemas, sub, f"{where}.{name}", seen)
        values = schema.get("additionalProperties")
        if isinstance(values, dict):
            found += [] if "maxProperties" in schema else [where]
            found += _unbounded(schemas, values, f"{where}{{}}", seen)
    return found


def test_every_string_list_and_map_a_body_can_hold_is_bounded(client):
    """A prior's source, a measurement's condition units, an iteration's effect name, the CCT window stresses
    and a material's effects had no bound. Free-form JSON values (``Any``) are bounded by the body's size and depth."""
    document = client.get(f"{API}/openapi.json").json()
    schemas, seen, found = document["components"]["schemas"], set(), []
    for operations in document["paths"].values():
        for operation in operations.values():
            body = operation.get("requestBody", {}).get("content", {}).get("application/json", {}).get("schema")
            if body is not None:
                found += _unbounded(schemas, body, "body", seen)
    assert found == []


def test_a_campaign_whose_response_cannot_be_built_leaves_no_row(s2, monkeypatch):
    """As for materials: the campaign was committed before its summary was built."""
    from service.api import campaigns as api

    client, _app, _settings = s2
    monkeypatch.setattr(api, "campaign_summary", fails_once(api.campaign_summary))
    client_500 = TestClient(client.app, base_url=LOCAL, raise_server_exceptions=False)
    r = client_500.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client)))
    assert r.status_code == 500
    assert client.get(f"{API}/campaigns").json()["items"] == []


def test_an_effect_parameter_refuses_a_boolean(client):
    body = {"evaluator": "analytic", "parameters": {"effects": {"rolling_epsd2": {"rolling_friction": True}}}}
    r = client.post(f"{API}/jobs", json=body)
    assert r.status_code == 422, r.text
    assert client.get(f"{API}/jobs").json()["total"] == 0
