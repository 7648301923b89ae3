"""Issue 13, limits and identity: one cost model for jobs, campaigns and schedules; identities that
cannot be forged off loopback; a per-client limit that holds under a burst; the bind check."""
from __future__ import annotations

import time
from concurrent.futures import ThreadPoolExecutor

import httpx
import pytest
from conftest_s2 import API, campaign_body, s2, s2_settings, thesis_material_id  # noqa: F401
from fastapi.testclient import TestClient
from service_net import LOCAL_BASE_URL

from engine.lab.presets import SCREENING
from service.app import create_app
from service.config import Settings
from service.security import check_bind


def locs(response) -> list[list]:
    return [err["loc"] for err in response.json()["detail"]]


def stroke_s() -> float:
    """One lid stroke of the screening CCT, at most: half the packing height at lab lid speed x factor."""
    return 0.5 * SCREENING.packing_height_m / (SCREENING.lab_lid_speed_m_s * SCREENING.default_speed_factor)


# -- the cost model --------------------------------------------------------------------------------

def test_every_cct_cycle_counts(client):
    """cct_cycles 1e9 passed when only the shear test was counted."""
    r = client.post(f"{API}/jobs", json={"evaluator": "analytic", "options": {"cct_cycles": 10**9}})
    assert r.status_code == 422 and ["body", "options", "cct_cycles"] in locs(r)
    limit = client.app.state.settings.max_simulated_time_s
    cycles = int(limit / (2 * stroke_s())) + 1  # the fewest cycles whose strokes alone exceed the limit
    r = client.post(f"{API}/jobs", json={"evaluator": "analytic", "test": "cct", "options": {"cct_cycles": cycles}})
    assert r.status_code == 422 and locs(r) == [["body", "options", "cct_cycles"]]
    message = r.json()["detail"][0]["msg"]
    assert f"limit of {limit:.0f} s" in message and "cct" in message
    assert client.get(f"{API}/jobs").json()["total"] == 0


def test_cost_model_counts_every_stage():
    from engine.lab.spec import JobSpec
    from engine.lab.stops import LEVEL_SETTLE_MAX_S, RAIN_SETTLE_MAX_S
    from service.limits import estimate

    FILL_SETTLE_S = RAIN_SETTLE_MAX_S + LEVEL_SETTLE_MAX_S  # fill.py: rain and settle, level and settle

    cct = estimate(JobSpec(test="cct"))
    assert cct.stages_s == pytest.approx({"fill": FILL_SETTLE_S, "cct": SCREENING.cct_cycles * 2 * stroke_s()})
    battery = estimate(JobSpec(options={"include_aor": True, "include_anchor": True}))
    assert set(battery.stages_s) == {"fill", "cct", "dst", "aor", "anchor"}
    # the largest packing decides the particle count: never fewer than the shear box alone
    assert battery.particles >= estimate(JobSpec(test="fill")).particles


def test_campaign_checks_every_design_run_at_creation(s2):
    """A draft with billions of particles used to be accepted and fail only on start."""
    client, _, _ = s2
    material_id = thesis_material_id(client)
    # screening spheres of 20 mm give ~840 particles; a tenth of the radius gives 1000x as many
    factors = [{"name": "particle_radius_m", "low": SCREENING.shapes[0].radius_min_m / 10,
                "high": SCREENING.shapes[0].radius_min_m},
               {"name": "friction_pp", "low": 0.3, "high": 1.0}]
    body = campaign_body(material_id, fidelity="screening", factors=factors, design={"type": "full", "centre_runs": 1})
    r = client.post(f"{API}/campaigns", json=body)
    assert r.status_code == 422 and locs(r) == [["body", "factors", "0", "low"]], r.text
    assert "particles" in r.json()["detail"][0]["msg"]
    too_long = campaign_body(material_id, fidelity="screening", options={"cct_cycles": 1000})
    r = client.post(f"{API}/campaigns", json=too_long)
    assert r.status_code == 422 and locs(r) == [["body", "options", "cct_cycles"]], r.text
    schedule = {"name": "nightly", "cron": "0 2 * * *", "template": too_long}
    r = client.post(f"{API}/schedules", json=schedule)
    assert r.status_code == 422 and locs(r) == [["body", "template", "options", "cct_cycles"]], r.text
    assert client.get(f"{API}/campaigns").json()["items"] == [] and client.get(f"{API}/schedules").json()["items"] == []


def test_design_size_is_refused_before_it_is_built(s2):
    """One preview within the schema (15 factors, 10 replicates: 2^15 x 10 runs) used 2 GB and 20 s."""
    client, _, settings = s2
    factors = [{"name": f"x{i}", "low": 0.0, "high": 1.0} for i in range(15)]
    started = time.monotonic()
    r = client.post(f"{API}/designs/preview", json={"factors": factors, "replicates": 10})
    assert r.status_code == 422 and locs(r) == [["body", "replicates"]]
    assert f"{2**15 * 10 + 3} runs" in r.json()["detail"][0]["msg"]  # + the 3 default centre runs
    assert time.monotonic() - started < 5.0
    # a resolution III fraction of the same 15 factors (16 runs) is fine
    generators = ["E=ABCD", "F=ABC", "G=ABD", "H=ACD", "J=BCD", "K=AB", "L=AC", "M=AD", "N=BC", "O=BD", "P=CD"]
    r = client.post(f"{API}/designs/preview", json={"factors": factors, "type": "fractional",
                                                    "generators": generators, "centre_runs": 0})
    assert r.status_code == 200, r.text
    assert r.json()["n_runs"] == 2 ** (15 - len(generators))
    big = campaign_body(thesis_material_id(client), design={"type": "full", "centre_runs": 0, "replicates": 10},
                        factors=[{"name": n, "low": lo, "high": hi} for n, lo, hi in [
                            ("friction_pp", 0.3, 1.0), ("friction_pw", 0.3, 0.6), ("damping_ratio", 0.1, 0.5),
                            ("local_damping", 0.0, 0.5), ("particle_density_kg_m3", 2300.0, 2700.0),
                            ("particle_stiffness_n_per_m", 1e6, 3e6), ("wall_stiffness_n_per_m", 1e7, 3e7),
                            ("shear_to_normal_stiffness_ratio", 0.5, 1.0)]])
    r = client.post(f"{API}/campaigns", json=big)  # 2^8 x 10 runs
    assert r.status_code == 422 and locs(r) == [["body", "design", "replicates"]], r.text
    assert str(settings.max_design_runs) in r.json()["detail"][0]["msg"]


# -- identity and the per-client limit -------------------------------------------------------------

def submit(client, headers=None):
    return client.post(f"{API}/jobs", json={"evaluator": "analytic"}, headers=headers or {})


def test_identity_comes_from_the_token_name_not_a_header(settings):
    named = settings.model_copy(update={"tokens": "alice:a-secret-0123456789,bob:b-secret-0123456789", "max_queued_jobs_per_client": 2})
    with TestClient(create_app(named), base_url=LOCAL_BASE_URL, client=("203.0.113.7", 4000)) as client:  # a remote peer
        alice = {"Authorization": "Bearer a-secret-0123456789"}
        for _ in range(2):
            r = submit(client, alice)
            assert r.status_code == 201 and r.json()["client_id"] == "token:alice"
        dodge = submit(client, {**alice, "X-Client-Id": "somebody-else"})  # changing the header does not help
        assert dodge.status_code == 429 and ["header", "X-Client-Id"] in locs(dodge)
        forged = submit(client, {"Authorization": "Bearer b-secret-0123456789", "X-Client-Id": "token:alice"})
        assert forged.status_code == 201 and forged.json()["client_id"] == "token:bob"
        assert submit(client, {"Authorization": "Bearer wrong"}).status_code == 401
        assert client.get(f"{API}/jobs").status_code == 401  # with tokens configured, reads need one too
        assert client.get(f"{API}/jobs", headers=alice).json()["total"] == 3


def test_peer_without_token_cannot_choose_an_identity_unless_a_listed_proxy(settings):
    for peer in ("203.0.113.9", "127.0.0.1"):  # remote, and loopback: neither is a proxy the operator listed
        with TestClient(create_app(settings), base_url=LOCAL_BASE_URL, client=(peer, 4000)) as client:
            r = submit(client, {"X-Client-Id": "lab-a"})
            assert r.status_code == 201 and r.json()["client_id"] == peer
    proxied = settings.model_copy(update={"trusted_proxies": "127.0.0.1"})
    with TestClient(create_app(proxied), base_url=LOCAL_BASE_URL, client=("127.0.0.1", 4000)) as client:
        r = submit(client, {"X-Client-Id": "lab-a"})  # the listed proxy names the client
        assert r.status_code == 201 and r.json()["client_id"] == "lab-a"


def test_burst_of_50_admits_exactly_the_limit(live_server):
    """The count-then-insert admitted 4 and 7 of a limit of 3; 50 concurrent submissions admit 3."""
    base, _, _ = live_server(workers=0, DEMCAL_MAX_QUEUED_JOBS_PER_CLIENT="3", DEMCAL_TRUSTED_PROXIES="127.0.0.1")

    def one(index: int) -> int:
        with httpx.Client(base_url=f"{base}/api/v1", timeout=60) as http:
            return http.post("/jobs", json={"evaluator": "analytic", "seed": index},
                             headers={"X-Client-Id": "burst"}).status_code

    with ThreadPoolExecutor(max_workers=50) as pool:
        codes = list(pool.map(one, range(50)))
    assert codes.count(201) == 3 and codes.count(429) == 47, sorted(codes)
    listing = httpx.get(f"{base}/api/v1/jobs", params={"limit": 100}).json()
    assert listing["total"] == 3 and {j["client_id"] for j in listing["items"]} == {"burst"}


# -- bind check --------------------------------------------------------------------------------------

@pytest.mark.parametrize("host", ["", " ", "0.0.0.0", "::", "192.0.2.10", "example.org"])
def test_bind_refuses_every_non_loopback_host_without_token(host):
    with pytest.raises(SystemExit, match="refusing to bind"):
        check_bind(Settings(host=host))
    check_bind(Settings(host=host, token="t-0123456789abcdef"))
    check_bind(Settings(host=host, tokens="alice:a-secret-0123456789"))


@pytest.mark.parametrize("host", ["127.0.0.1", "127.0.0.2", "localhost", "::1"])
def test_bind_allows_loopback_without_token(host):
    check_bind(Settings(host=host))


def test_serve_with_empty_host_refuses(tmp_path):
    from service.cli import main

    with pytest.raises(SystemExit, match="every interface"):
        main(["serve", "--host", "", "--db", str(tmp_path / "x.db")])


def test_schedule_firing_over_todays_limits_is_skipped_with_the_reason(s2):
    """Limits lowered after the schedule was made: the firing says why instead of starting a doomed campaign."""
    from datetime import datetime

    from service.models.schedule import Schedule
    from service.schedules.scheduler import Scheduler

    client, app, settings = s2
    body = {"name": "nightly", "cron": "0 2 * * *", "template": campaign_body(thesis_material_id(client))}
    schedule = client.post(f"{API}/schedules", json=body).json()
    due = datetime(2026, 11, 21, 2, 0)
    with app.state.session_factory() as session:
        session.get(Schedule, schedule["id"]).next_run_at = due
        session.commit()
    lowered = settings.model_copy(update={"max_particles": 1})
    assert Scheduler(app.state.session_factory, lowered).tick(due) == []
    (firing,) = client.get(f"{API}/schedules/{schedule['id']}/firings").json()["items"]
    assert firing["campaign_id"] is None and "particles" in firing["skipped_reason"]
    assert client.get(f"{API}/campaigns").json()["items"] == []
