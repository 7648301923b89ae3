"""What a web page in the user's browser can do to the default (loopback, tokenless) service: nothing
(issue 32, item 3; service.browser_guard). Each test here passed requests the service answered before."""
from __future__ import annotations

import base64
import hashlib
import re

import httpx
import pytest
from fastapi.testclient import TestClient
from service_net import LOCAL_BASE_URL, LOOPBACK_PEER

from service.app import create_app
from service.browser_guard import same_site
from service.config import settings_from_env

API = "/api/v1"
FORM = {"Content-Type": "application/x-www-form-urlencoded"}


def queued_job(client) -> int:
    response = client.post(f"{API}/jobs", json={"evaluator": "analytic"})
    assert response.status_code == 201, response.text
    return response.json()["id"]


def status(client, job_id: int) -> str:
    return client.get(f"{API}/jobs/{job_id}").json()["status"]


def test_cross_site_form_post_cannot_cancel_a_job(client):
    """What ``<form method=post action=http://127.0.0.1:8000/api/v1/jobs/1/cancel>`` on another site sends."""
    job = queued_job(client)
    r = client.post(f"{API}/jobs/{job}/cancel", content=b"x=1",
                    headers={**FORM, "Origin": "https://evil.example", "Referer": "https://evil.example/page"})
    assert r.status_code == 403, r.text
    assert r.json()["detail"][0]["loc"] == ["header", "Origin"]
    assert status(client, job) == "queued"


@pytest.mark.parametrize("content_type", ["text/plain", "text/plain;charset=UTF-8", FORM["Content-Type"],
                                          "multipart/form-data; boundary=x"])
def test_form_content_types_are_refused_even_without_origin(client, content_type):
    """A browser that sends no Origin (or a page that hides its Referer) still sends a form's content type."""
    job = queued_job(client)
    r = client.post(f"{API}/jobs/{job}/cancel", content=b"", headers={"Content-Type": content_type})
    assert r.status_code == 415, r.text
    assert status(client, job) == "queued"
    r = client.post(f"{API}/jobs", content=b'{"evaluator": "analytic"}', headers={"Content-Type": content_type})
    assert r.status_code == 415


def test_foreign_referer_without_origin_is_refused(client):
    job = queued_job(client)
    r = client.post(f"{API}/jobs/{job}/cancel", headers={"Referer": "http://evil.example/x"})
    assert r.status_code == 403 and r.json()["detail"][0]["loc"] == ["header", "Referer"]
    r = client.post(f"{API}/jobs/{job}/cancel", headers={"Origin": "null"})  # a sandboxed frame or a file: page
    assert r.status_code == 403
    r = client.post(f"{API}/jobs/{job}/cancel", headers={"Origin": "http://127.0.0.1:3000"})  # another local app
    assert r.status_code == 403
    assert status(client, job) == "queued"


def test_the_pages_own_requests_and_plain_clients_still_write(client):
    """Same origin (the page's fetch), and no Origin, Referer or Content-Type at all (curl, the CLI, httpx)."""
    job = queued_job(client)
    page = {"Origin": LOCAL_BASE_URL, "Referer": f"{LOCAL_BASE_URL}/#/jobs"}
    r = client.post(f"{API}/jobs/{job}/cancel", headers=page)
    assert r.status_code == 200 and r.json()["status"] == "cancelled"
    r = client.post(f"{API}/jobs/{job}/retry")
    assert r.status_code == 200 and r.json()["status"] == "queued"
    r = client.post(f"{API}/jobs", json={"evaluator": "analytic"},
                    headers={**page, "Content-Type": "application/json; charset=utf-8"})
    assert r.status_code == 201
    r = client.post(f"{API}/jobs/{job}/cancel", headers={"Referer": f"{LOCAL_BASE_URL}/"})
    assert r.status_code == 200


@pytest.mark.parametrize("host", ["evil.example", "evil.example:8000", "127.0.0.1.evil.example", "192.168.1.5",
                                  "localhost.", "[::2]", "a b"])
def test_foreign_host_is_refused(client, host):
    """A DNS-rebinding page's requests name its own host: neither reads nor writes are answered."""
    job = queued_job(client)
    r = client.get(f"{API}/jobs", headers={"Host": host})
    assert r.status_code == 400 and r.json()["detail"][0]["loc"] == ["header", "Host"]
    assert client.get("/", headers={"Host": host}).status_code == 400
    r = client.post(f"{API}/jobs/{job}/cancel", headers={"Host": host, "Origin": f"http://{host}"})
    assert r.status_code == 400 and status(client, job) == "queued"


@pytest.mark.parametrize("host", ["127.0.0.1", "127.0.0.1:8000", "localhost", "LocalHost:8123", "[::1]",
                                  "[::1]:8000"])
def test_loopback_hosts_pass(client, host):
    assert client.get(f"{API}/health", headers={"Host": host}).status_code == 200
    job = queued_job(client)
    r = client.post(f"{API}/jobs/{job}/cancel", headers={"Host": host, "Origin": f"http://{host.lower()}"})
    assert r.status_code == 200, r.text


@pytest.mark.parametrize(("origin", "host", "same"), [
    ("https://calib.lab.example", "calib.lab.example", True),  # behind a TLS proxy: the service sees http
    ("http://calib.lab.example", "calib.lab.example", True),
    ("https://calib.lab.example:8443", "calib.lab.example:8443", True),
    ("http://localhost:3000", "localhost", False),  # another local web app
    ("http://localhost:8000", "localhost:8001", False),
    ("http://127.0.0.1:8000", "localhost:8000", False),  # another name is another origin
    ("http://[::1]:8000", "[::1]:8000", True),
    ("null", "127.0.0.1:8000", False),
    ("http://127.0.0.1:8000/path?q=1", "127.0.0.1:8000", True),  # a Referer
])
def test_same_site_compares_host_and_port(origin, host, same):
    assert same_site(origin, host) is same


def test_allowed_hosts_setting(settings):
    """DEMCAL_ALLOWED_HOSTS adds names (a wildcard bind reached by the machine's name); '*' allows any; a
    specific bound host is allowed by itself."""
    extra = settings_from_env({"DEMCAL_ALLOWED_HOSTS": "calib.lab.example, 10.0.0.5"},
                              **{**settings.model_dump(), "allowed_hosts": None})
    assert extra.allowed_hosts == "calib.lab.example, 10.0.0.5"
    with TestClient(create_app(extra), base_url=LOCAL_BASE_URL, client=LOOPBACK_PEER) as client:
        assert client.get(f"{API}/health", headers={"Host": "calib.lab.example:8000"}).status_code == 200
        assert client.get(f"{API}/health", headers={"Host": "10.0.0.5"}).status_code == 200
        assert client.get(f"{API}/health", headers={"Host": "localhost"}).status_code == 200
        assert client.get(f"{API}/health", headers={"Host": "other.example"}).status_code == 400
    with TestClient(create_app(settings.model_copy(update={"allowed_hosts": "*"})), base_url="http://anything",
                    client=LOOPBACK_PEER) as client:
        assert client.get(f"{API}/health").status_code == 200
    bound = settings.model_copy(update={"host": "192.0.2.10", "token": "s3cret-token-of-16"})
    with TestClient(create_app(bound), base_url="http://192.0.2.10:8000", client=LOOPBACK_PEER) as client:
        assert client.get(f"{API}/health").status_code == 200
        assert client.get(f"{API}/health", headers={"Host": "192.0.2.11"}).status_code == 400


def test_pages_carry_csp_and_frame_headers(client):
    for path in ("/", "/static/js/app.js", f"{API}/health", f"{API}/docs", f"{API}/redoc", f"{API}/jobs/999"):
        headers = client.get(path).headers
        csp = [part.strip() for part in headers["content-security-policy"].split(";")]
        assert "default-src 'self'" in csp and "frame-ancestors 'none'" in csp and "object-src 'none'" in csp
        script_src = next(part for part in csp if part.startswith("script-src "))
        assert "'unsafe-inline'" not in script_src and "'unsafe-eval'" not in script_src
        assert headers["x-frame-options"] == "DENY"
        assert headers["x-content-type-options"] == "nosniff"
        assert headers["referrer-policy"] == "same-origin"
    # refusals carry them too
    assert client.get("/", headers={"Host": "evil.example"}).headers["x-frame-options"] == "DENY"


def test_swagger_pages_inline_script_is_allowed_by_its_hash_only(client):
    response = client.get(f"{API}/docs")
    scripts = re.findall(r"<script>(.*?)</script>", response.text, re.DOTALL)
    assert scripts, "Swagger UI's start-up script is inline"
    for body in scripts:
        digest = base64.b64encode(hashlib.sha256(body.encode()).digest()).decode()
        assert f"'sha256-{digest}'" in response.headers["content-security-policy"]


def test_live_server_refuses_rebinding_and_cross_site_forms(live_server):
    """The same rules through uvicorn, as a browser meets them."""
    base, _env, _proc = live_server()
    job = httpx.post(f"{base}{API}/jobs", json={"evaluator": "analytic"}).json()["id"]
    assert httpx.get(f"{base}{API}/jobs/{job}", headers={"Host": "rebound.example"}).status_code == 400
    port = base.rsplit(":", 1)[1]
    assert httpx.get(f"{base}{API}/jobs/{job}", headers={"Host": f"localhost:{port}"}).status_code == 200
    r = httpx.post(f"{base}{API}/jobs/{job}/cancel", content=b"", headers={**FORM, "Origin": "https://evil.example"})
    assert r.status_code == 403
    assert httpx.post(f"{base}{API}/jobs/{job}/cancel", content=b"a=b", headers=FORM).status_code == 415
    assert httpx.get(f"{base}{API}/jobs/{job}").json()["status"] == "queued"
    assert httpx.post(f"{base}{API}/jobs/{job}/cancel").json()["status"] == "cancelled"
