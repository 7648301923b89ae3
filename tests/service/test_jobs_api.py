"""Every jobs/health endpoint, success and error paths, through an HTTP client against the app."""
from __future__ import annotations

import pytest
from fastapi.testclient import TestClient
from service_net import LOCAL_BASE_URL

from service.app import create_app
from service.migrate import head_revision
from service.workers.local import Worker

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)

API = "/api/v1"


def submit(client, **body):
    body.setdefault("evaluator", "analytic")
    return client.post(f"{API}/jobs", json=body)


def run_all(client) -> None:
    """Run queued jobs in-process with a worker on the app's own database."""
    app = client.app
    worker = Worker(app.state.session_factory, app.state.settings, "api-test")
    while worker.run_one() is not None:
        pass


def locs(response) -> list[list]:
    return [err["loc"] for err in response.json()["detail"]]


def test_health(client):
    body = client.get(f"{API}/health").json()
    assert body["status"] == "ok" and body["database"] == "ok"
    assert body["schema_revision"] == head_revision()
    assert body["jobs"] == {}


def test_openapi_lists_job_routes(client):
    paths = client.get(f"{API}/openapi.json").json()["paths"]
    for path in ("/api/v1/jobs", "/api/v1/jobs/{job_id}", "/api/v1/jobs/{job_id}/result",
                 "/api/v1/jobs/{job_id}/curves", "/api/v1/jobs/{job_id}/cancel", "/api/v1/jobs/{job_id}/retry",
                 "/api/v1/health"):
        assert path in paths


def test_submit_single_test_and_battery(client):
    r = submit(client, test="dst", fidelity="screening", seed=11, parameters={"friction_pp": 0.5},
               options={"dst_normal_stresses_pa": [10e3, 20e3]}, priority=3)
    assert r.status_code == 201
    job = r.json()
    assert r.headers["location"].endswith(f"/api/v1/jobs/{job['id']}")
    assert job["status"] == "queued" and job["test"] == "dst" and job["seed"] == 11 and job["priority"] == 3
    assert job["spec"]["parameters"]["friction_pp"] == 0.5  # full spec kept for replay
    assert job["spec"]["options"]["dst_normal_stresses_pa"] == [10e3, 20e3]
    battery = submit(client).json()
    assert battery["test"] == "battery" and battery["evaluator"] == "analytic"


def test_the_largest_seed_is_stored_and_replayed(client):
    """Seeds run to 2^32 - 1, past PostgreSQL's INTEGER: there this answered 500 until the column was a BIGINT."""
    largest = 2**32 - 1
    job = submit(client, seed=largest, idempotency_key="largest-seed").json()
    assert job["seed"] == largest and job["spec"]["seed"] == largest
    assert client.get(f"/api/v1/jobs/{job['id']}").json()["seed"] == largest
    assert submit(client, seed=largest, idempotency_key="largest-seed").json()["id"] == job["id"]


@pytest.mark.parametrize("body, loc", [
    ({"parameters": {"friction_pp": -0.1}}, ["body", "parameters", "friction_pp"]),
    ({"test": "triaxial"}, ["body", "test"]),
    ({"evaluator": "python"}, ["body", "evaluator"]),
    ({"seed": -1}, ["body", "seed"]),
    ({"unknown": 1}, ["body", "unknown"]),
    ({"options": {"speed_factor": 0}}, ["body", "options", "speed_factor"]),
    ({"parameters": {"particle_radius_m": 0.001}}, ["body", "parameters", "particle_radius_m"]),  # particle limit
    ({"options": {"speed_factor": 0.001}}, ["body", "options", "speed_factor"]),  # simulated time limit
    ({"fidelity": "thesis", "parameters": {"particle_radius_m": 0.01}}, ["body", "parameters", "particle_radius_m"]),
    # the lab's pre-run checks, refused at submission instead of failing the job later
    ({"options": {"cct_max_stress_pa": 20e3, "dst_normal_stresses_pa": [10e3, 30e3]}},
     ["body", "options", "dst_normal_stresses_pa"]),
    ({"options": {"moving_average_span": 20}}, ["body", "options", "moving_average_span"]),
])
def test_submit_rejects_bad_input_naming_the_field(client, body, loc):
    r = submit(client, **body)
    assert r.status_code == 422
    assert loc in locs(r)


def test_idempotency_key_body_and_header(client):
    first = submit(client, seed=1, idempotency_key="run-17")
    again = submit(client, seed=1, idempotency_key="run-17")
    assert (first.status_code, again.status_code) == (201, 200)
    assert first.json()["id"] == again.json()["id"]
    clash = submit(client, seed=2, idempotency_key="run-17")
    assert clash.status_code == 409 and ["body", "idempotency_key"] in locs(clash)
    via_header = client.post(f"{API}/jobs", json={"evaluator": "analytic", "seed": 5}, headers={"Idempotency-Key": "h1"})
    again = client.post(f"{API}/jobs", json={"evaluator": "analytic", "seed": 5}, headers={"Idempotency-Key": "h1"})
    assert via_header.json()["id"] == again.json()["id"] and again.status_code == 200
    assert client.get(f"{API}/jobs").json()["total"] == 2


def test_queued_job_limit_per_client(settings):
    # the loopback peer stands for a proxy the operator listed: only then may X-Client-Id name the client
    limited = settings.model_copy(update={"max_queued_jobs_per_client": 3, "trusted_proxies": "127.0.0.1"})
    with TestClient(create_app(limited), base_url=LOCAL_BASE_URL, client=("127.0.0.1", 50000)) as client:
        for seed in range(3):
            assert submit(client, seed=seed).status_code == 201
        r = submit(client, seed=9)
        assert r.status_code == 429 and ["header", "X-Client-Id"] in locs(r)
        other = client.post(f"{API}/jobs", json={"evaluator": "analytic"}, headers={"X-Client-Id": "lab-b"})
        assert other.status_code == 201 and other.json()["client_id"] == "lab-b"


def test_list_and_filter(client):
    a = submit(client, test="dst", campaign_id=4).json()
    b = submit(client, test="cct").json()
    c = submit(client, test="dst", evaluator="dem").json()
    client.post(f"{API}/jobs/{b['id']}/cancel")
    listing = client.get(f"{API}/jobs").json()
    assert listing["total"] == 3 and [j["id"] for j in listing["items"]] == [c["id"], b["id"], a["id"]]
    ids = lambda q: [j["id"] for j in client.get(f"{API}/jobs?{q}").json()["items"]]  # noqa: E731
    assert ids("test=dst") == [c["id"], a["id"]]
    assert ids("status=cancelled") == [b["id"]]
    assert ids("campaign_id=4") == [a["id"]]
    assert ids("evaluator=dem") == [c["id"]]
    assert ids("status=queued&test=dst&evaluator=analytic") == [a["id"]]
    page = client.get(f"{API}/jobs?limit=1&offset=1").json()
    assert [j["id"] for j in page["items"]] == [b["id"]] and page["total"] == 3
    for bad, loc in [("status=done", ["query", "status"]), ("limit=0", ["query", "limit"]),
                     ("offset=-1", ["query", "offset"]), ("test=foo", ["query", "test"])]:
        r = client.get(f"{API}/jobs?{bad}")
        assert r.status_code == 422 and loc in locs(r)


def test_list_by_origin_direct_campaign_or_all(client):
    """The page lists the jobs a user submitted without the batteries campaigns queued (origin=direct)."""
    direct = submit(client, test="dst").json()
    battery = submit(client, test="dst", campaign_id=4).json()
    ids = lambda q: [j["id"] for j in client.get(f"{API}/jobs?{q}").json()["items"]]  # noqa: E731
    assert ids("origin=direct") == [direct["id"]]
    assert ids("origin=campaign") == [battery["id"]]
    assert ids("origin=all") == ids("") == [battery["id"], direct["id"]]  # all is the default
    assert client.get(f"{API}/jobs?origin=direct").json()["total"] == 1
    assert ids("origin=direct&campaign_id=4") == []  # the filters combine
    r = client.get(f"{API}/jobs?origin=mine")
    assert r.status_code == 422 and ["query", "origin"] in locs(r)


def test_get_status_and_missing(client):
    job = submit(client).json()
    got = client.get(f"{API}/jobs/{job['id']}").json()
    assert got["status"] == "queued" and got["progress"] == {"fraction": 0.0, "phase": None}
    r = client.get(f"{API}/jobs/999")
    assert r.status_code == 404 and locs(r) == [["path", "job_id"]]
    r = client.get(f"{API}/jobs/abc")
    assert r.status_code == 422 and ["path", "job_id"] in locs(r)


def test_result_and_curves(client):
    job = submit(client, test="battery", seed=3).json()
    for path in ("result", "curves", "curves/mohr_coulomb"):
        r = client.get(f"{API}/jobs/{job['id']}/{path}")
        assert r.status_code == 409, path  # not finished yet
    run_all(client)
    status = client.get(f"{API}/jobs/{job['id']}").json()
    assert status["status"] == "succeeded" and status["result_available"] and status["progress"]["fraction"] == 1.0
    assert status["engine_version"].startswith("analytic-") and status["wall_time_s"] >= 0
    record = client.get(f"{API}/jobs/{job['id']}/result").json()
    assert record["provenance"]["seed"] == 3 and record["curves"]
    quantities = {(p["test"], p["quantity"]) for p in record["properties"]}
    assert ("dst", "friction_angle_deg") in quantities and ("fill", "bulk_density_kg_m3") in quantities
    lean = client.get(f"{API}/jobs/{job['id']}/result?include_curves=false").json()
    assert "curves" not in lean and lean["properties"] == record["properties"]
    index = client.get(f"{API}/jobs/{job['id']}/curves").json()  # names, columns and lengths, no data
    assert set(index) == set(record["curves"])
    for name, columns in record["curves"].items():
        assert index[name] == {"columns": sorted(columns), "points": len(next(iter(columns.values())))}
    curve = client.get(f"{API}/jobs/{job['id']}/curves/mohr_coulomb").json()
    assert len(curve["normal_stress_pa"]) == len(curve["residual_shear_stress_pa"])
    r = client.get(f"{API}/jobs/{job['id']}/curves/nope")
    assert r.status_code == 404 and locs(r) == [["path", "name"]]
    assert client.get(f"{API}/jobs/999/result").status_code == 404


def test_cancel_and_retry(client):
    job = submit(client).json()
    r = client.post(f"{API}/jobs/{job['id']}/cancel")
    assert r.status_code == 200 and r.json()["status"] == "cancelled"
    r = client.post(f"{API}/jobs/{job['id']}/cancel")
    assert r.status_code == 409 and locs(r) == [["path", "job_id"]]
    r = client.post(f"{API}/jobs/{job['id']}/retry")
    assert r.status_code == 200 and r.json()["status"] == "queued" and r.json()["attempts"] == 0
    r = client.post(f"{API}/jobs/{job['id']}/retry")
    assert r.status_code == 409  # queued jobs cannot be retried
    run_all(client)
    assert client.post(f"{API}/jobs/{job['id']}/cancel").status_code == 409  # succeeded
    assert client.post(f"{API}/jobs/{job['id']}/retry").status_code == 409
    assert client.post(f"{API}/jobs/999/cancel").status_code == 404
    assert client.post(f"{API}/jobs/999/retry").status_code == 404


def test_cancel_running_job_is_accepted(client):
    job = submit(client).json()
    from service import queue

    with client.app.state.session_factory() as s:
        queue.claim_next(s, "w", 30)
    r = client.post(f"{API}/jobs/{job['id']}/cancel")
    assert r.status_code == 202 and r.json()["status"] == "running" and r.json()["cancel_requested"]


def test_token_guards_writes(settings):
    with TestClient(create_app(settings.model_copy(update={"token": "s3cret-0123456789ab"})), base_url=LOCAL_BASE_URL) as client:
        r = submit(client)
        assert r.status_code == 401 and locs(r) == [["header", "Authorization"]]
        assert client.post(f"{API}/jobs", json={}, headers={"Authorization": "Bearer wrong"}).status_code == 401
        ok = client.post(f"{API}/jobs", json={"evaluator": "analytic"}, headers={"Authorization": "Bearer s3cret-0123456789ab"})
        assert ok.status_code == 201
        assert client.get(f"{API}/jobs").status_code == 401  # reads need the token too (DEMCAL_OPEN_READS opens them)
        assert client.get(f"{API}/jobs", headers={"Authorization": "Bearer s3cret-0123456789ab"}).status_code == 200


def test_refuses_public_bind_without_token(settings):
    with pytest.raises(SystemExit, match="DEMCAL_TOKEN"):
        create_app(settings.model_copy(update={"host": "0.0.0.0"}))
    create_app(settings.model_copy(update={"host": "0.0.0.0", "token": "t-0123456789abcdef"}))


def test_limits_follow_settings(settings):
    from engine.lab.spec import JobSpec
    from engine.lab.cost import estimated_particles, estimated_simulated_time_s

    spec = JobSpec()
    particles, sim_s = estimated_particles(spec), estimated_simulated_time_s(spec)
    for update, loc in [({"max_particles": particles - 1}, ["body", "parameters", "particle_radius_m"]),
                        ({"max_simulated_time_s": sim_s * 0.99}, ["body", "options", "speed_factor"])]:
        with TestClient(create_app(settings.model_copy(update=update)), base_url=LOCAL_BASE_URL) as client:
            r = submit(client)
            assert r.status_code == 422 and locs(r) == [loc]
    roomy = {"max_particles": particles, "max_simulated_time_s": sim_s * 1.01}
    with TestClient(create_app(settings.model_copy(update=roomy)), base_url=LOCAL_BASE_URL) as client:
        assert submit(client).status_code == 201


def test_particle_estimate_matches_appendix_a():
    """Table A.7's screening set-up holds ~840 spheres of 20 mm below the levelling height."""
    from engine.lab.presets import SCREENING
    from engine.lab.spec import JobSpec
    from engine.lab.cost import estimated_particles

    below_level = estimated_particles(JobSpec()) / SCREENING.fill_margin
    assert abs(below_level - 840) / 840 < 0.10


def test_elongated_clumps_cost_two_spheres_each():
    """The screening clumps have the sphere's volume (engine/lab/shape.py): as many bodies fill the box,
    each of two spheres, and a step's cost follows the spheres."""
    from engine.lab.spec import JobSpec, MicroParameters
    from engine.lab.cost import estimated_particles

    spheres = estimated_particles(JobSpec())
    clumps = estimated_particles(JobSpec(parameters=MicroParameters(clump_aspect_ratio=1.5)))
    assert abs(clumps - 2 * spheres) <= 2
