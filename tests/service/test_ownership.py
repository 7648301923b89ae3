"""Issue 32, item 2: users own their work. With named tokens, one user cancelled another's job (200);
without a token every read showed every job; a client held at its queue limit queued on through
schedules (each was its own client) and through forged X-Forwarded-For / X-Client-Id headers."""
from __future__ import annotations

from datetime import datetime

import httpx
import pytest
from conftest_s2 import API, THESIS_MATERIAL, campaign_body, editable_thesis_copy, running_app, s2_settings
from fastapi.testclient import TestClient
from service_net import LOCAL_BASE_URL

from service.app import create_app
from service.security import check_bind, token_users

ALICE, BOB, ROOT = "alice-token-0123456789", "bob-token-0123456789ab", "root-token-0123456789a"
TOKENS = f"alice:{ALICE},bob:{BOB},root:{ROOT}:admin"


def auth(token: str) -> dict:
    return {"Authorization": f"Bearer {token}"}


def msg(response) -> str:
    return response.json()["detail"][0]["msg"]


@pytest.fixture
def team(tmp_path):
    """The real app (bundled material seeded) with three users, root an administrator."""
    with running_app(s2_settings(tmp_path).model_copy(update={"tokens": TOKENS})) as (client, app):
        yield client, app


def bundled_id(client, token: str) -> int:
    page = client.get(f"{API}/materials", headers=auth(token)).json()
    return next(m["id"] for m in page["items"] if m["name"] == THESIS_MATERIAL)


def job_of(client, token: str, **body) -> dict:
    r = client.post(f"{API}/jobs", json={"evaluator": "analytic", **body}, headers=auth(token))
    assert r.status_code == 201, r.text
    return r.json()


# -- writes --------------------------------------------------------------------------------------

def test_a_user_cannot_cancel_another_s_job_but_an_administrator_can(team):
    client, _ = team
    job = job_of(client, ALICE)
    assert job["owner"] == "alice"
    for action in ("cancel", "retry"):
        r = client.post(f"{API}/jobs/{job['id']}/{action}", headers=auth(BOB))
        assert r.status_code == 403 and r.json()["detail"][0]["loc"] == ["path", "job_id"], r.text
        assert "belongs to 'alice'" in msg(r) and "administrator" in msg(r)
    assert client.get(f"{API}/jobs/{job['id']}", headers=auth(ALICE)).json()["status"] == "queued"  # untouched
    r = client.post(f"{API}/jobs/{job['id']}/cancel", headers=auth(ROOT))
    assert r.status_code == 200 and r.json()["status"] == "cancelled"
    assert client.post(f"{API}/jobs/{job['id']}/retry", headers=auth(ALICE)).status_code == 200  # her own


def test_materials_campaigns_and_schedules_are_their_owner_s(team):
    client, _ = team
    bundled = bundled_id(client, ALICE)
    # the bundled material stays read-only for everyone, administrators too (409, not 403)
    for token in (ALICE, ROOT):
        assert client.delete(f"{API}/materials/{bundled}", headers=auth(token)).status_code == 409
    copy = client.post(f"{API}/materials/{bundled}/copy", json={"name": "alice's"}, headers=auth(ALICE)).json()
    assert copy["owner"] == "alice"
    measurement = copy["measurements"][0]
    assert client.delete(f"{API}/materials/{copy['id']}/measurements/{measurement['id']}",
                         headers=auth(BOB)).status_code == 403
    assert client.delete(f"{API}/materials/{copy['id']}", headers=auth(BOB)).status_code == 403
    # copying reads the original: bob gets his own copy of alice's material
    bobs = client.post(f"{API}/materials/{copy['id']}/copy", json={"name": "bob's"}, headers=auth(BOB))
    assert bobs.status_code == 201 and bobs.json()["owner"] == "bob"

    campaign = client.post(f"{API}/campaigns", json=campaign_body(copy["id"]), headers=auth(ALICE)).json()
    assert campaign["owner"] == "alice"
    r = client.post(f"{API}/campaigns/{campaign['id']}/start", headers=auth(BOB))
    assert r.status_code == 403 and "campaign" in msg(r) and "'alice'" in msg(r)
    r = client.post(f"{API}/jobs", json={"evaluator": "analytic", "campaign_id": campaign["id"]}, headers=auth(BOB))
    assert r.status_code == 403 and r.json()["detail"][0]["loc"] == ["body", "campaign_id"]
    assert client.post(f"{API}/campaigns/{campaign['id']}/start", headers=auth(ROOT)).status_code == 200

    schedule = client.post(f"{API}/schedules", json={"name": "nightly", "cron": "0 2 * * *",
                                                     "template": campaign_body(copy["id"])}, headers=auth(ALICE)).json()
    assert schedule["owner"] == "alice"
    assert client.patch(f"{API}/schedules/{schedule['id']}", json={"enabled": False}, headers=auth(BOB)).status_code == 403
    assert client.delete(f"{API}/schedules/{schedule['id']}", headers=auth(BOB)).status_code == 403
    assert client.patch(f"{API}/schedules/{schedule['id']}", json={"enabled": False}, headers=auth(ALICE)).status_code == 200
    assert client.delete(f"{API}/schedules/{schedule['id']}", headers=auth(ROOT)).status_code == 204


def test_rows_without_an_owner_are_changed_by_administrators_only(tmp_path):
    """Rows from before ownership (or from a server without tokens) belong to nobody."""
    settings = s2_settings(tmp_path)
    with running_app(settings) as (client, _):  # first without tokens: one user, nothing checked
        job = client.post(f"{API}/jobs", json={"evaluator": "analytic"}).json()
        assert job["owner"] is None
        material = editable_thesis_copy(client)
    with running_app(settings.model_copy(update={"tokens": TOKENS})) as (client, _):
        r = client.post(f"{API}/jobs/{job['id']}/cancel", headers=auth(ALICE))
        assert r.status_code == 403 and "has no owner" in msg(r)
        assert client.delete(f"{API}/materials/{material}", headers=auth(ALICE)).status_code == 403
        assert client.post(f"{API}/jobs/{job['id']}/cancel", headers=auth(ROOT)).status_code == 200
        assert client.delete(f"{API}/materials/{material}", headers=auth(ROOT)).status_code == 204


def test_without_tokens_everything_stays_as_it_was(client):
    """A single user on loopback: no owners to check, reads open."""
    job = client.post(f"{API}/jobs", json={"evaluator": "analytic"}).json()
    assert client.get(f"{API}/jobs").status_code == 200
    assert client.post(f"{API}/jobs/{job['id']}/cancel").status_code == 200


# -- a schedule's jobs are its owner's ------------------------------------------------------------

def test_a_schedule_s_jobs_count_against_its_owner_s_limit(tmp_path):
    """A client held at 3 queued 15 jobs through 4 schedules: each schedule was a client of its own."""
    from service.campaigns.runner import CampaignRunner
    from service.models.schedule import Schedule
    from service.schedules.scheduler import Scheduler

    settings = s2_settings(tmp_path).model_copy(update={"tokens": TOKENS, "max_queued_jobs_per_client": 3})
    with running_app(settings) as (client, app):
        material = bundled_id(client, ALICE)
        for seed in range(3):
            job_of(client, ALICE, seed=seed)
        assert client.post(f"{API}/jobs", json={"evaluator": "analytic", "seed": 9}, headers=auth(ALICE)).status_code == 429
        ids = [client.post(f"{API}/schedules", json={"name": f"s{i}", "cron": "0 2 * * *",
                                                     "template": campaign_body(material)}, headers=auth(ALICE)).json()["id"]
               for i in range(2)]
        due = datetime(2026, 11, 21, 2, 0)
        with app.state.session_factory() as session:
            for schedule_id in ids:
                session.get(Schedule, schedule_id).next_run_at = due
            session.commit()
        started = Scheduler(app.state.session_factory, settings).tick(due)
        assert len(started) == 2
        CampaignRunner(app.state.session_factory, settings).tick()
        jobs = client.get(f"{API}/jobs", params={"status": "queued"}, headers=auth(ALICE)).json()
        assert jobs["total"] == 3 and {j["client_id"] for j in jobs["items"]} == {"token:alice"}
        for campaign_id in started:
            campaign = client.get(f"{API}/campaigns/{campaign_id}", headers=auth(ALICE)).json()
            assert campaign["owner"] == "alice" and campaign["status"] == "running"
        # bob's queue is his own
        assert client.post(f"{API}/jobs", json={"evaluator": "analytic"}, headers=auth(BOB)).status_code == 201


# -- identity headers ----------------------------------------------------------------------------------

def submit(client, headers: dict):
    return client.post(f"{API}/jobs", json={"evaluator": "analytic"}, headers=headers)


def test_forwarding_headers_from_a_peer_not_listed_are_ignored(settings):
    limited = settings.model_copy(update={"max_queued_jobs_per_client": 2})
    with TestClient(create_app(limited), base_url=LOCAL_BASE_URL, client=("127.0.0.1", 4000)) as client:
        for i in range(2):
            r = submit(client, {"X-Forwarded-For": f"198.51.100.{i}", "X-Client-Id": f"forged-{i}"})
            assert r.status_code == 201 and r.json()["client_id"] == "127.0.0.1"
        assert submit(client, {"X-Forwarded-For": "198.51.100.9", "X-Client-Id": "forged-9"}).status_code == 429


def test_forwarding_headers_from_a_listed_proxy_name_the_client(settings):
    proxied = settings.model_copy(update={"trusted_proxies": "127.0.0.1, 10.0.0.0/8"})
    with TestClient(create_app(proxied), base_url=LOCAL_BASE_URL, client=("127.0.0.1", 4000)) as client:
        # the nearest address that is not a listed proxy: what the client wrote to the left of it is its word
        r = submit(client, {"X-Forwarded-For": "192.0.2.66, 203.0.113.5, 10.1.2.3"})
        assert r.json()["client_id"] == "203.0.113.5"
        assert submit(client, {"X-Client-Id": "lab-a"}).json()["client_id"] == "lab-a"
    with TestClient(create_app(proxied), base_url=LOCAL_BASE_URL, client=("192.0.2.1", 4000)) as client:
        assert submit(client, {"X-Forwarded-For": "203.0.113.5"}).json()["client_id"] == "192.0.2.1"
    with pytest.raises(SystemExit, match="DEMCAL_TRUSTED_PROXIES"):
        check_bind(settings.model_copy(update={"trusted_proxies": "10.0.0.0/33"}))


def test_served_by_demcal_serve_a_forged_x_forwarded_for_is_no_new_client(live_server):
    """uvicorn believed X-Forwarded-For from loopback: 20 of 20 forged addresses were 20 clients."""
    base, _, _ = live_server(workers=0, DEMCAL_MAX_QUEUED_JOBS_PER_CLIENT="2")
    codes = [httpx.post(f"{base}/api/v1/jobs", json={"evaluator": "analytic"},
                        headers={"X-Forwarded-For": f"198.51.100.{i}"}, timeout=30).status_code for i in range(3)]
    assert codes == [201, 201, 429]


# -- reads --------------------------------------------------------------------------------------------

def test_reads_need_a_token_when_tokens_are_configured(settings):
    with TestClient(create_app(settings.model_copy(update={"tokens": TOKENS})), base_url=LOCAL_BASE_URL) as client:
        for path in ("/jobs", "/materials", "/campaigns", "/schedules", "/jobs/1"):
            r = client.get(f"{API}{path}")
            assert r.status_code == 401 and r.headers["WWW-Authenticate"] == "Bearer", path
            assert r.json()["detail"][0]["loc"] == ["header", "Authorization"]
        assert client.get(f"{API}/jobs", headers=auth("not-a-token-0123456789")).status_code == 401
        assert client.get(f"{API}/jobs", headers=auth(BOB)).status_code == 200
        # open: the page and its files (the token is typed into it), health and the OpenAPI document
        for path in ("/", "/static/js/core.js", f"{API}/health", f"{API}/openapi.json", f"{API}/docs", f"{API}/redoc"):
            assert client.get(path).status_code == 200, path
    opened = settings.model_copy(update={"tokens": TOKENS, "open_reads": True})
    with TestClient(create_app(opened), base_url=LOCAL_BASE_URL) as client:
        assert client.get(f"{API}/jobs").status_code == 200
        assert submit(client, {}).status_code == 401  # writes still need one


# -- roles on tokens ---------------------------------------------------------------------------------

def test_roles_on_named_tokens(settings):
    users = token_users(settings.model_copy(update={"tokens": TOKENS}))
    assert {(u.name, u.admin) for u in users.values()} == {("alice", False), ("bob", False), ("root", True)}
    single = token_users(settings.model_copy(update={"token": ROOT}))
    assert [(u.name, u.admin) for u in single.values()] == [("token", True)]  # the operator's single token
    for bad in (f"alice:{ALICE}:boss", f"alice:{ALICE}:admin:x"):
        with pytest.raises(SystemExit, match="name:token or name:token:admin"):
            token_users(settings.model_copy(update={"tokens": bad}))


def test_a_user_cannot_replace_another_s_rig_and_a_bundled_one_is_read_only_for_all(team):
    """Rigs are owned like materials: bob may not replace alice's record (403); the bundled rigs stay 409 for
    everyone, the administrator included (results name them)."""
    from test_rigs_api import _thesis_record

    client, _ = team
    made = client.post(f"{API}/rigs", json=_thesis_record("alice 300 mm box"), headers=auth(ALICE))
    assert made.status_code == 201 and made.json()["owner"] == "alice", made.text
    rig = made.json()
    body = {**_thesis_record("alice 300 mm box"), "description": "changed by bob"}
    r = client.put(f"{API}/rigs/{rig['id']}", json=body, headers=auth(BOB))
    assert r.status_code == 403 and r.json()["detail"][0]["loc"] == ["path", "rig_id"], r.text
    assert client.put(f"{API}/rigs/{rig['id']}", json=body, headers=auth(ALICE)).status_code == 200
    bundled = next(x for x in client.get(f"{API}/rigs", headers=auth(ROOT)).json()["items"] if x["bundled"])
    assert client.put(f"{API}/rigs/{bundled['id']}", json={**_thesis_record(bundled["name"])},
                      headers=auth(ROOT)).status_code == 409
