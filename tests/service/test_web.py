"""The web UI: pages, scripts and styles served by the app itself, nothing from the web, API paths that exist."""
from __future__ import annotations

import re
import shutil
import subprocess

import pytest

from conftest_s2 import s2  # noqa: F401

IMPORT_RE = re.compile(r"""(?:import|from)\s*(?:[^"';]*?\s+from\s+)?["'](\./[^"']+)["']""")
API_CALL_RE = re.compile(r"""(?:api|optional)\(\s*(?:`([^`]*)`|"([^"]*)")""")


def _fetch_modules(client) -> dict[str, str]:
    """index.html's module and every module it imports, transitively, through HTTP."""
    html = client.get("/").text
    pending = re.findall(r'<script[^>]+src="([^"]+)"', html)
    seen: dict[str, str] = {}
    while pending:
        path = pending.pop()
        if path in seen:
            continue
        response = client.get(path)
        assert response.status_code == 200, path
        assert "javascript" in response.headers["content-type"], path
        seen[path] = response.text
        base = path.rsplit("/", 1)[0]
        pending += [f"{base}/{m[2:]}" for m in IMPORT_RE.findall(response.text)]
    return seen


def test_index_and_assets_are_served_locally(s2):
    client, _, _ = s2
    index = client.get("/")
    assert index.status_code == 200 and index.headers["content-type"].startswith("text/html")
    html = index.text
    for href in re.findall(r'(?:href|src)="([^"#]+)"', html):
        assert href.startswith("/"), f"external or relative asset {href}"
        assert client.get(href).status_code == 200, href
    css = client.get("/static/style.css")
    assert css.status_code == 200 and "text/css" in css.headers["content-type"]
    modules = _fetch_modules(client)
    assert {"/static/js/app.js", "/static/js/core.js", "/static/js/jobs.js", "/static/js/materials.js",
            "/static/js/campaigns.js", "/static/js/campaign.js", "/static/js/plot.js", "/static/js/live.js"} <= set(modules)
    for path, text in {**modules, "/": html, "/static/style.css": css.text}.items():
        urls = re.findall(r"https?://[^\s\"'`)]+", text)
        assert urls in ([], ["http://www.w3.org/2000/svg"]), (path, urls)  # SVG namespace is a name, not a fetch
    assert client.get("/static/js/nothing.js").status_code == 404


def test_favicon_is_served_not_a_404(s2):
    """Browsers ask every page's host for /favicon.ico (the API docs name no icon): the app's own SVG."""
    client, _, _ = s2
    icon = client.get("/favicon.ico")
    assert icon.status_code == 200 and icon.headers["content-type"].startswith("image/svg+xml")
    assert icon.content == client.get("/static/favicon.svg").content and b"<svg" in icon.content
    assert '<link rel="icon" href="/static/favicon.svg"' in client.get("/").text


def test_pages_call_only_existing_api_endpoints(s2):
    client, _, _ = s2
    paths = client.get("/api/v1/openapi.json").json()["paths"]
    templates = [re.compile("^" + re.sub(r"\{[^}]+\}", "[^/]+", p[len("/api/v1"):]) + "$") for p in paths]
    calls = set()
    for text in _fetch_modules(client).values():
        for literal in API_CALL_RE.findall(text):
            # `/jobs/${id}/cancel` -> /jobs/1/cancel; a query string is not part of the path
            calls.add(re.sub(r"\$\{[^}]*\}", "1", literal[0] or literal[1]).split("?")[0])
    assert {"/jobs", "/jobs/1/cancel", "/materials/1/measurements", "/campaigns/1/report", "/schedules/1",
            "/campaigns/1/start", "/campaigns/1/models", "/campaigns/1/iterations", "/campaigns/1/history", "/effects", "/evaluators", "/jobs/1/result",
            "/openapi.json"} <= calls
    for call in calls - {"/openapi.json"}:
        assert any(t.match(call) for t in templates), call


def test_ui_pages_show_campaign_and_material_data_through_the_api(s2):
    """What the pages render comes from these endpoints; check the fields the scripts read exist."""
    client, _, _ = s2
    campaigns_js = client.get("/static/js/campaign_report.js").text
    for field in ("measured_uncertainty", "prediction_interval", "confirmed", "standardised_residual",
                  "reachability", "reachable", "uncertainty_assumed"):
        assert field in campaigns_js
    materials_js = client.get("/static/js/materials.js").text
    material = client.get("/api/v1/materials").json()["items"][0]["measurements"][0]
    for field in ("mean", "standard_uncertainty", "values", "reported_replicates", "condition"):
        assert f"m.{field}" in materials_js and field in material
    assert client.get("/ui", follow_redirects=False).status_code in (307, 302)


@pytest.mark.skipif(shutil.which("node") is None, reason="node not installed")
def test_scripts_parse(s2, tmp_path):
    client, _, _ = s2
    for path, text in _fetch_modules(client).items():
        target = tmp_path / path.rsplit("/", 1)[1].replace(".js", ".mjs")
        target.write_text(text)
        result = subprocess.run(["node", "--check", str(target)], capture_output=True, text=True, timeout=60)
        assert result.returncode == 0, (path, result.stderr)


def test_charts_library_is_vendored_with_its_licence(s2):
    """The chart library the modules import is served by the app, with its licence; nothing from a CDN."""
    client, _, _ = s2
    plot = client.get("/static/js/plot.js").text
    (library,) = re.findall(r'from "(\.\./vendor/[^"]+)"', plot)
    path = "/static/js/" + library
    path = re.sub(r"/js/\.\./", "/", path)
    response = client.get(path)
    assert response.status_code == 200 and "javascript" in response.headers["content-type"]
    folder = path.rsplit("/", 1)[0]
    assert "Apache License" in client.get(f"{folder}/LICENSE").text


def test_api_docs_pages_load_only_the_services_own_files(s2):
    """Swagger UI and ReDoc pages name only local assets (the browser test checks the rendering offline)."""
    client, _, _ = s2
    for page, expected in (("/api/v1/docs", "swagger-ui-bundle.js"), ("/api/v1/redoc", "redoc.standalone.js")):
        response = client.get(page)
        assert response.status_code == 200 and expected in response.text
        assets = re.findall(r"""(?:href|src|url)\s*[=:]\s*["']([^"']+)["']""", response.text)
        assert assets and all(a.startswith("/") for a in assets), (page, assets)
        assert not re.search(r"https?://(?!www\.w3\.org)", response.text), page
        for asset in assets:
            assert client.get(asset).status_code == 200, asset
    redoc = client.get("/static/vendor/redoc-2.5.4/redoc.standalone.js").text
    assert "cdn.redoc.ly" not in redoc  # its logo was its one request outside the service


def test_report_gives_the_reachability_cutoff(s2):
    """The page draws the cutoff that decides 'reachable'; the report says it rather than the page guessing."""
    from conftest_s2 import API, campaign_body, run_to_end, thesis_material_id
    from calibration.report import REACHABLE_LIMIT

    client, app, settings = s2
    body = campaign_body(thesis_material_id(client), diagnose=False)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    report = client.get(f"{API}/campaigns/{cid}/report").json()
    assert report["reachable_limit"] == REACHABLE_LIMIT
    for row in report["targets"]:
        if row.get("reachability") is not None:
            assert row["reachable"] == (row["reachability"] <= REACHABLE_LIMIT)
