"""The shareable report (issue 30 item 5): a campaign's verdict, targets, diagnosis and history as one
self-contained HTML file with inline SVG charts, readable offline.

The first tests read the file as text (in process, analytic evaluator). The browser test follows the
campaign page's link in headless Chromium (Debian's, through Playwright as tests/service/test_browser.py
does), downloads the file, opens it from disk and checks that no request leaves it and no console
error occurs; its screenshot goes to $DEMCAL_SCREENSHOT_DIR."""
from __future__ import annotations

import os
import re
from html.parser import HTMLParser
from pathlib import Path

import pytest

from conftest_s2 import API, campaign_body, run_to_end, s2, thesis_material_id  # noqa: F401
from test_campaign_cli import server  # noqa: F401  (a real HTTP server in this process)

from service.export import svg

HOSTILE_NAME = 'loop <script>alert("x")</script> & co'


class _Collect(HTMLParser):
    """Every tag with its attributes, and the text of <style> (the only place CSS may be)."""

    def __init__(self):
        super().__init__()
        self.tags: list[tuple[str, dict]] = []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    handle_startendtag = handle_starttag


def _two_iterations(client, app, settings) -> int:
    """A campaign whose first iteration misses the friction angle, the diagnosis names the effect, and a
    second iteration adds it (as test_campaign_loop's first test)."""
    body = campaign_body(thesis_material_id(client), targets=None, name=HOSTILE_NAME)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    top = client.get(f"{API}/campaigns/{cid}/diagnosis").json()["ranking"][0]["effect"]
    assert client.post(f"{API}/campaigns/{cid}/iterations", json={"add_effect": top}).status_code == 201
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    return cid


def test_the_report_is_one_self_contained_file(s2):
    client, app, settings = s2
    cid = _two_iterations(client, app, settings)
    response = client.get(f"{API}/campaigns/{cid}/report.html")
    assert response.status_code == 200 and response.headers["content-type"].startswith("text/html")
    html = response.text
    report = client.get(f"{API}/campaigns/{cid}/report").json()
    first = client.get(f"{API}/campaigns/{cid}/report", params={"number": 1}).json()
    # the latest iteration's verdict, every target, the history of both iterations
    assert report["verdict"] in html and report["meaning"] in html.replace("&#x27;", "'")
    for target in report["targets"]:
        assert target["quantity"] in html
    assert "iteration 2 of 2" in html
    tags = _Collect()
    tags.feed(html)
    names = [t for t, _ in tags.tags]
    assert names.count("svg") >= 2  # parity plot(s) and the error history
    # nothing that loads anything: no script, no link, no image, no src or href; CSS only inline
    assert not {"script", "link", "img", "iframe", "object", "embed"} & set(names)
    for tag, attrs in tags.tags:
        assert not {"src", "href", "srcset", "action", "style"} & set(attrs), (tag, attrs)
    assert "url(" not in html and "@import" not in html
    # the one URL in the file is SVG's namespace name, which nothing fetches
    assert set(re.findall(r"https?://[^\"' )]+", html)) == {"http://www.w3.org/2000/svg"}
    # text from the database is escaped, never markup
    assert "<script>" not in html and "loop &lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt; &amp; co" in html
    # one parity point per modelled target with a confirmed value; the history has both iterations
    modelled = [t for t in report["targets"] if t.get("confirmed") is not None]
    assert len(re.findall(r'class="point"', html)) == len(modelled)
    assert len(re.findall(r'class="line-point"', html)) == 2
    # the diagnosis of the first iteration is the history's; the latest report's diagnosis section says what it has
    assert ("No diagnosis in this iteration" in html) == ("diagnosis" not in report)
    first_html = client.get(f"{API}/campaigns/{cid}/report.html", params={"number": 1}).text
    assert first["diagnosis"]["ranking"][0]["effect"] in first_html and "iteration 1 of 2" in first_html
    saved = client.get(f"{API}/campaigns/{cid}/report.html", params={"download": "true"})
    assert saved.headers["content-disposition"] == f'attachment; filename="campaign-{cid}-report.html"'


def test_nice_ticks_are_round_steps_covering_the_range():
    # at most 5 ticks: a step of at least (high - low) / 4, rounded up to 1, 2 or 5 times a power of ten
    assert svg.nice_ticks(0.0, 10.0) == [0.0, 5.0, 10.0]  # 2.5 -> 5
    assert svg.nice_ticks(0.0, 1.6) == [0.0, 0.5, 1.0, 1.5]  # 0.4 -> 0.5
    assert svg.nice_ticks(1374.0, 1411.0) == [1380.0, 1390.0, 1400.0, 1410.0]  # raw 9.25 -> step 10


def test_the_parity_plot_puts_agreeing_points_on_the_diagonal():
    """Points with confirmed == measured lie on the drawn diagonal; one above it is above (smaller y)."""
    text = svg.parity_plot([{"label": "a", "measured": 1.0, "u": 0.1, "confirmed": 1.0, "interval": (0.9, 1.1)},
                            {"label": "b", "measured": 3.0, "u": None, "confirmed": 3.0, "interval": None},
                            {"label": "c", "measured": 2.0, "u": None, "confirmed": 2.5, "interval": None}], "Pa")
    x1, y1, x2, y2 = map(float, re.search(r'<line x1="([\d.]+)" y1="([\d.]+)" x2="([\d.]+)" y2="([\d.]+)" '
                                          r'class="diagonal"', text).groups())
    points = [tuple(map(float, m)) for m in re.findall(r'<circle cx="([\d.]+)" cy="([\d.]+)" r="4" class="point"', text)]
    assert len(points) == 3

    def diagonal_y(x):
        return y1 + (y2 - y1) * (x - x1) / (x2 - x1)

    for cx, cy in points[:2]:
        assert cy == pytest.approx(diagonal_y(cx), abs=0.15)  # pixel rounding of one decimal
    assert points[2][1] < diagonal_y(points[2][0]) - 5


def test_error_history_draws_one_point_per_iteration_and_series():
    entries = [{"number": 1, "weighted_rms": 5.1, "chi2_per_dof": 79.4, "noise_band": [0.0, 3.8]},
               {"number": 2, "weighted_rms": 0.9, "chi2_per_dof": 1.2, "noise_band": [0.0, 3.0]}]
    text = svg.error_history(entries)
    assert text.count('class="line-point"') == 2 and text.count('class="line2-point"') == 2
    assert text.count('class="band"><title>') == 2


# -- in a browser -----------------------------------------------------------------------------------

def _browser_reason():
    from browser_support import missing_browser_reason

    return missing_browser_reason()


def test_the_page_links_the_report_and_the_file_reads_offline_in_chromium(server, tmp_path: Path):
    reason = _browser_reason()
    if reason:
        from browser_support import REQUIRE_ENV

        if os.environ.get(REQUIRE_ENV) == "1":
            raise RuntimeError(f"{REQUIRE_ENV}=1 but the browser tests cannot run: {reason}")
        pytest.skip(f"browser tests: {reason}")
    import httpx
    from playwright.sync_api import sync_playwright

    from browser_support import launch, screenshot_dir, watch_page
    url, app, settings = server
    with httpx.Client(base_url=url) as http:
        cid = _two_iterations(http, app, settings)
    shots = screenshot_dir(tmp_path / "shots")
    with sync_playwright() as playwright:
        browser = launch(playwright)
        try:
            context = browser.new_context(viewport={"width": 1200, "height": 900}, accept_downloads=True)
            context.set_default_timeout(60_000)
            page = context.new_page()
            watch = watch_page(page, url)
            page.goto(f"{url}/#/campaigns/{cid}")
            link = page.locator('a[data-export="report.html"]')
            link.wait_for()
            assert link.get_attribute("href") == f"{API}/campaigns/{cid}/report.html?number=2&download=true"
            assert page.locator('a[data-export="material-card"]').count() == 1
            page.locator("p.exports").screenshot(path=str(shots / "campaign-export-links.png"))
            with page.expect_download() as download:
                link.click()
            saved = tmp_path / download.value.suggested_filename
            download.value.save_as(saved)
            assert saved.name == f"campaign-{cid}-report.html"
            assert not watch.problems(), watch.problems()

            # the saved file, opened from disk with every request but the file itself refused
            offline = context.new_page()
            file_url = saved.resolve().as_uri()
            requests, errors = [], []

            def route(route_obj):
                if route_obj.request.url == file_url:
                    route_obj.continue_()
                else:
                    requests.append(route_obj.request.url)
                    route_obj.abort()

            offline.route("**/*", route)
            offline.on("console", lambda msg: errors.append(msg.text) if msg.type == "error" else None)
            offline.on("pageerror", lambda exc: errors.append(str(exc)))
            offline.on("request", lambda req: requests.append(req.url) if req.url != file_url else None)
            offline.goto(file_url)
            offline.wait_for_load_state("load")
            assert offline.locator("#verdict strong").inner_text() == \
                httpx.get(f"{url}{API}/campaigns/{cid}/report").json()["verdict"]
            assert offline.locator("#parity svg").count() >= 1
            box = offline.locator("#parity svg").first.bounding_box()
            assert box and box["width"] > 200 and box["height"] > 200  # drawn, not an empty element
            offline.screenshot(path=str(shots / "campaign-report-html.png"), full_page=True)
            assert not requests, requests
            assert not errors, errors
        finally:
            browser.close()


def test_the_parameters_table_notes_a_widened_interval_and_each_trade():
    """The exported report says what the page says of the intervals (issue 33 item 3): which interval points
    measured on the batteries widened, with the threshold, and each pair that trades (tests/service/
    intervals_case.py's intervals, tier A seed 11's rolling trade)."""
    from html import escape

    from intervals_case import trading_intervals

    from service.export.report_html import _parameters

    intervals = trading_intervals()
    report = {"optimum": {name: row["value"] for name, row in intervals["parameters"].items()}, "intervals": intervals}
    text = _parameters(report, [], None)
    (name,) = intervals["measured_points"]["widened"]
    threshold = intervals["measured_points"]["threshold"]
    assert (f"widened to the points measured on the batteries that fit within chi2 {escape(f'{threshold:.4g}')} of "
            f"the best: {escape(name)}</p>") in text
    for trade in intervals["trades"]:
        assert escape(trade["message"]) in text
