"""The web interface in a real browser: headless Chromium (Debian's package) driven by Playwright,
against a real ``demcal serve`` with a temp data dir, workers and the campaign ticker.

Each test fails on any browser console error, uncaught page error, or request to anything but the
service (all such requests are aborted: this is how the UI and the API docs are shown to work
offline). Screenshots go to $DEMCAL_SCREENSHOT_DIR (CI keeps them as artefacts; default a temp dir;
docs/screenshots/refresh.py points it at docs/screenshots). Campaigns use the analytic evaluator.
"""
from __future__ import annotations

import gzip
import json
import os
import re
from datetime import datetime, timezone
from pathlib import Path

import pytest

from calibration.evaluator_registry import names
from browser_support import REQUIRE_ENV, launch, missing_browser_reason, screenshot_dir, start_service, stop_service, watch_page

_REASON = missing_browser_reason()
if _REASON and os.environ.get(REQUIRE_ENV) == "1":
    raise RuntimeError(f"{REQUIRE_ENV}=1 but the browser tests cannot run: {_REASON}")
pytestmark = pytest.mark.skipif(_REASON is not None, reason=f"browser tests: {_REASON}")

RECORDED_DEM = Path(__file__).parent / "data" / "dem_screening_battery_result.json.gz"
TIMEOUT_MS = 90_000  # a whole analytic iteration takes a few seconds; shared CI machines are slower


@pytest.fixture(scope="module")
def service(tmp_path_factory):
    svc = start_service(tmp_path_factory.mktemp("browser-service"), workers=1)
    yield svc
    stop_service(svc.proc)


@pytest.fixture(scope="module")
def browser():
    from playwright.sync_api import sync_playwright

    with sync_playwright() as playwright:
        chromium = launch(playwright)
        yield chromium
        chromium.close()


@pytest.fixture(scope="module")
def shots(tmp_path_factory):
    return screenshot_dir(tmp_path_factory.mktemp("screenshots"))


@pytest.fixture
def page(browser, service, shots, request):
    """A fresh page watched for errors; its screenshot is saved whatever the outcome."""
    context = browser.new_context(viewport={"width": 1280, "height": 900})
    context.set_default_timeout(TIMEOUT_MS)
    pg = context.new_page()
    pg.watch = watch_page(pg, service.base_url)
    yield pg
    try:
        pg.screenshot(path=str(shots / f"{request.node.name}.png"), full_page=os.environ.get("DEMCAL_SCREENSHOT_FULL_PAGE", "1") == "1")
    finally:
        context.close()
    problems = pg.watch.problems()
    assert not problems, problems


def open_view(page, service, hash_: str):
    page.goto(f"{service.base_url}/{hash_}")


def expect_text(page, selector: str, pattern: str):
    from playwright.sync_api import expect

    expect(page.locator(selector).first).to_contain_text(re.compile(pattern), timeout=TIMEOUT_MS)


def section_shot(page, shots, title: str, name: str):
    """One card of a page, for docs/screenshots (smaller than the whole page)."""
    card = page.locator("section.card", has=page.locator("h3", has_text=re.compile("^" + re.escape(title)))).first
    card.scroll_into_view_if_needed()
    card.screenshot(path=str(shots / f"{name}.png"))


def open_report_serving(page, service, name: str, **parts) -> int:
    """A completed thesis campaign's page, its first report served with ``parts`` (a polish, intervals) made by
    the library loop in place of its own; the campaign's id."""
    cid = thesis_campaign_completed(service, name)
    report = service.api("GET", f"/campaigns/{cid}/report", params={"number": 1}).json()
    page.route(re.compile(rf".*/api/v1/campaigns/{cid}/report\?number=1$"),
               lambda route: route.fulfill(json={**report, **parts}))
    open_view(page, service, f"#/campaigns/{cid}")
    return cid


def thesis_campaign_completed(service, name: str) -> int:
    """A campaign on the thesis aggregate (conftest_s2's settings) created, started and waited for through the API;
    its id. For the tests that serve a page an iteration's report with one part made elsewhere."""
    import time

    from conftest_s2 import campaign_body

    material = service.api("GET", "/materials", params={"limit": 200}).json()["items"]
    thesis = next(m for m in material if m["name"] == "thesis-coarse-aggregate")
    cid = service.api("POST", "/campaigns", json=campaign_body(thesis["id"], name=name)).json()["id"]
    assert service.api("POST", f"/campaigns/{cid}/start").status_code < 300
    deadline = time.monotonic() + TIMEOUT_MS / 1000
    while service.api("GET", f"/campaigns/{cid}").json()["status"] != "completed":
        assert time.monotonic() < deadline, "the campaign did not complete"
        time.sleep(0.5)
    return cid


def test_campaign_loop_create_start_diagnose_add_effect_error_falls(page, service, shots):
    """The loop as a user walks it: form -> Start -> failing targets and the effect ranking -> add the
    effect -> iteration 2 completes on its own (live refresh) and its error is below iteration 1's."""
    open_view(page, service, "#/campaigns")
    form = page.locator("form#new-campaign")
    form.locator("input[name=name]").fill("browser loop")
    form.locator("select[name=material_id]").select_option(label="thesis-coarse-aggregate")
    assert form.locator("select[name=evaluator]").input_value() == "dem"  # CampaignCreate's default, JobSubmit's too
    form.locator("select[name=evaluator]").select_option("analytic")
    form.locator("select[name=fidelity]").select_option("thesis")
    form.locator("input[name=seed]").fill("11")
    names = form.locator("select[name=factor_name]")
    assert [names.nth(i).input_value() for i in range(3)] == ["particle_density_kg_m3", "particle_stiffness_n_per_m", "friction_pp"]
    page.screenshot(path=str(shots / "campaign-new.png"))
    form.get_by_role("button", name="Create (draft)").click()
    page.wait_for_url(re.compile(r"#/campaigns/\d+$"))
    campaign_id = int(page.url.rsplit("/", 1)[1])
    expect_text(page, "h2", "browser loop")
    expect_text(page, "h2 .status", "draft")

    page.locator("button[data-action=Start]").click()
    # no reload: the page refreshes itself until the report is there
    expect_text(page, "section.verdict h3", "targets out of reach|model misses the measurements")
    expect_text(page, "h2 .status", "completed")
    # the optimum the report is made at: the surfaces' (polishing skipped) or polished on the batteries
    expect_text(page, "section.verdict", r"Polishing on the batteries: (skipped|\d+ Gauss-Newton step)")
    failing = page.locator("section.card:has(h3:text('Targets')) tr:has(.target-fails)")
    assert failing.count() >= 1
    assert "friction angle (deg)" in " ".join(failing.all_inner_texts())  # named for people since issue 31
    assert page.locator("section.verdict").count() == 1 and page.get_by_text("Verdict:").count() == 1  # printed once
    # the ranking chart and table name the effect; the first significant one can be added
    expect_text(page, "section.diagnosis h3", "Diagnosis: ")
    add = page.locator("section.diagnosis form.add-effect").first
    top = add.get_attribute("data-effect")
    assert top in ("rolling_epsd2", "particle_shape"), top
    assert page.locator("section.diagnosis [aria-label='effect ranking'] svg").count() == 1
    expect_text(page, "section.history .chi2dof[data-iteration='1']", r"\d")
    assert_diagnosis_fits(page)
    # the candidates these targets cannot see are marked so in the table, not as merely "not significant"
    diagnosis = service.api("GET", f"/campaigns/{campaign_id}/diagnosis").json()
    significant = {r["effect"] for r in diagnosis["ranking"] if r["significant"]}
    unseen = [u["effect"] for u in diagnosis["unseen"] if u["effect"] not in significant]
    # one overall E' target: Hertz-Mindlin, matched to kp, changes nothing kp cannot absorb
    assert "hertz_mindlin" in unseen
    assert page.locator("section.diagnosis .unseen").count() == len(unseen)
    assert_parity_axes_end_on_ticks(page)
    assert not re.search(r"\b(fill|cct|dst|aor|anchor)__", page.locator("main").inner_text())  # no response keys
    for title, name in (("Verdict", "campaign-verdict"), ("Targets", "campaign-targets"), ("Across conditions", "campaign-conditions"),
                        ("Diagnosis", "campaign-diagnosis"), ("Fitted response surfaces", "campaign-anova")):
        section_shot(page, shots, title, name)

    add.locator("button").click()
    expect_text(page, "nav.iterations", f"2 · {top}")
    expect_text(page, "h2 .status", "completed")
    expect_text(page, "section.history .chi2dof[data-iteration='2']", r"\d")
    expect_text(page, "nav.iterations a.selected", f"2 · {top}")
    chi2 = {n: float(page.locator(f"section.history .chi2dof[data-iteration='{n}']").inner_text()) for n in (1, 2)}
    assert chi2[2] < chi2[1], chi2
    assert page.locator("section.history [aria-label='error history'] svg").count() == 1
    section_shot(page, shots, "Across iterations", "campaign-history")
    # the API agrees with what the page shows
    history = service.api("GET", f"/campaigns/{campaign_id}/history").json()["iterations"]
    assert [it["effects"] for it in history] == [[], [top]]
    assert abs(history[1]["chi2_per_dof"] - chi2[2]) <= 1e-3 * history[1]["chi2_per_dof"]
    # the second iteration reused the first's batteries on its design's low face: the row says how many
    reused = history[1]["batteries"]["reused"]
    assert reused >= 8 and f"(+{reused} reused)" in page.locator("section.history .batteries").nth(1).inner_text()
    # the added effect's trace, a factor of iteration 2 only, draws that iteration's design range
    factors = service.api("GET", f"/campaigns/{campaign_id}/iterations/2").json()["parameters"]["factors"]
    added = next(f for f in factors if f["name"].startswith("effects."))
    trace = page.locator(f"section.history [aria-label='trace {added['name']}']")
    from playwright.sync_api import expect
    expect(trace.locator("svg")).to_have_count(1, timeout=TIMEOUT_MS)
    drawn = page.evaluate("""async (el) => {
        const echarts = await import("/static/vendor/echarts-6.1.0/echarts.esm.min.js");  // the page's own module instance
        const series = echarts.getInstanceByDom(el).getOption().series;
        return ["bounds", "bounds "].map((n) => series.find((s) => s.name === n).data.filter((p) => p[1] !== "-")); }""",
                          trace.element_handle())
    for points, bound in zip(drawn, (added["low"], added["high"])):
        assert len(points) == 2 and all(1.5 < x < 2.5 and y == bound for x, y in points), (points, bound)
    # its bar is the report's 95 % interval, which never leaves the box (an optimiser's +-2 sd once did)
    bars = page.evaluate("""async (el) => {
        const echarts = await import("/static/vendor/echarts-6.1.0/echarts.esm.min.js");
        return echarts.getInstanceByDom(el).getOption().series.find((s) => s.name === "95 % interval").data; }""",
                         trace.element_handle())
    interval = history[1]["parameter_interval"][added["name"]]
    assert [b[-2:] for b in bars] == [interval] and added["low"] <= interval[0] <= interval[1] <= added["high"]
    # iteration 1 stays readable from the selector
    page.locator("nav.iterations a", has_text=re.compile(r"^1")).click()
    expect_text(page, "p.active-effects", "Iteration 1 model: no contact effects")
    page.screenshot(path=str(shots / "campaign-iteration-1.png"))


def overflowing(page, selector: str) -> list[str]:
    """The cells, inputs and scroll boxes under ``selector`` whose content is wider than their box
    (scrollWidth > clientWidth: clipped, cut off, or hidden behind a sideways scroll)."""
    return page.evaluate("""(selector) => [...document.querySelectorAll(selector)].flatMap((root) =>
        [...root.querySelectorAll("td, th, input, .scroll, p, h3, h4")])
        .filter((el) => el.scrollWidth > el.clientWidth + 1)
        .map((el) => `${el.tagName.toLowerCase()} ${el.scrollWidth}>${el.clientWidth}: ${(el.value || el.textContent).slice(0, 60)}`)""",
                         selector)


def assert_diagnosis_fits(page):
    """The diagnosis panel at 1280 px: no cell, input or table clipped; the ranking chart's labels
    whole, inside the chart and clear of each other (the critical value's above the axis labels)."""
    assert page.viewport_size["width"] == 1280
    assert overflowing(page, "section.diagnosis") == []
    chart = page.locator("section.diagnosis [aria-label='effect ranking']")
    texts = chart.evaluate("""(box) => { const outer = box.getBoundingClientRect();
        return [...box.querySelectorAll("svg text")].filter((t) => t.textContent.trim()).map((t) => {
          const r = t.getBoundingClientRect();
          return { text: t.textContent, left: r.left - outer.left, right: r.right - outer.left, top: r.top - outer.top,
                   bottom: r.bottom - outer.top, width: outer.width, height: outer.height }; }); }""")
    assert texts and not [t for t in texts if "…" in t["text"] or "..." in t["text"]], texts
    outside = [t["text"] for t in texts if t["left"] < 0 or t["right"] > t["width"] + 0.5 or t["top"] < 0 or t["bottom"] > t["height"] + 0.5]
    assert outside == [], outside
    critical = next(t for t in texts if t["text"].startswith("critical"))
    overlaps = [t["text"] for t in texts if t is not critical and t["left"] < critical["right"] and critical["left"] < t["right"]
                and t["top"] < critical["bottom"] and critical["top"] < t["bottom"]]
    assert overlaps == [], (critical, overlaps)
    # the strength bounds show whole in their inputs (1e8, not "1000000(")
    for box in page.locator("section.diagnosis form.add-effect input").all():
        assert box.input_value() and box.evaluate("(el) => el.scrollWidth <= el.clientWidth"), box.input_value()


def assert_parity_axes_end_on_ticks(page):
    """Each parity chart's axes start and end on a multiple of their tick interval (round labels)."""
    charts = page.locator("section.card [aria-label^='parity ']")
    assert charts.count() >= 1
    for handle in charts.element_handles():
        axes = page.evaluate("""async (el) => {
            const echarts = await import("/static/vendor/echarts-6.1.0/echarts.esm.min.js");
            const option = echarts.getInstanceByDom(el).getOption();
            return [...option.xAxis, ...option.yAxis].map((a) => [a.min, a.max, a.interval]); }""", handle)
        for low, high, step in axes:
            for end in (low, high):
                assert abs(end / step - round(end / step)) < 1e-9, (low, high, step)


def test_job_submission_with_an_effect_shows_its_curves(page, service, shots):
    open_view(page, service, "#/submit")
    form = page.locator("form#submit-job")
    evaluator = form.locator("select[name=evaluator]")
    # the form is drawn once its catalogues (evaluators, lab tests, effects) have arrived: wait for it
    from playwright.sync_api import expect

    expect(evaluator.locator("option").first).to_be_attached(timeout=TIMEOUT_MS)
    # the options are the registry's (GET /evaluators), the default is JobSubmit's (OpenAPI)
    assert evaluator.locator("option").evaluate_all("options => options.map((o) => o.value)") == names()
    assert evaluator.input_value() == "dem"
    evaluator.select_option("analytic")
    form.locator("select[name=fidelity]").select_option("thesis")
    form.locator("input[name=effect][value=rolling_epsd2]").check()
    form.locator("input[name='effect:rolling_epsd2:rolling_friction']").fill("0.3")
    page.screenshot(path=str(shots / "job-submit.png"))
    form.get_by_role("button", name="Queue job").click()
    page.wait_for_url(re.compile(r"#/jobs/\d+$"))
    job_id = int(page.url.rsplit("/", 1)[1])
    expect_text(page, "h2 .status", "succeeded")  # refreshed live from queued
    chart = page.locator("[aria-label='DST: Mohr-Coulomb envelope']")
    expect_text(page, "[aria-label='DST: Mohr-Coulomb envelope']", "normal stress \\(kPa\\)")
    assert "shear stress (kPa)" in chart.inner_text() and "envelope: φ" in chart.inner_text()
    spec = service.api("GET", f"/jobs/{job_id}").json()["spec"]
    assert spec["parameters"]["effects"] == {"rolling_epsd2": {"rolling_friction": 0.3}}


def _insert_job(service, **fields) -> int:
    """A finished job written straight into the service's database (the workers only claim queued ones)."""
    from service.db import make_engine, make_session_factory
    from service.models.job import Job

    now = datetime.now(timezone.utc).replace(tzinfo=None)
    engine = make_engine(service.database_url)
    try:
        with make_session_factory(engine)() as session:
            job = Job(evaluator="dem", fidelity="screening", seed=1, attempts=1, created_at=now, started_at=now,
                      finished_at=now, progress_fraction=1.0, progress_phase="done", **fields)
            session.add(job)
            session.commit()
            return job.id
    finally:
        engine.dispose()


@pytest.mark.skipif(not RECORDED_DEM.exists(), reason="recorded DEM result missing")
def test_dem_result_curves_one_quantity_per_axis(page, service, shots):
    """A screening battery as the DEM engine recorded it (fill, CCT, DST at four loads, angle of repose),
    replayed: the views engineers read, each axis one quantity with its unit."""
    result = json.loads(gzip.decompress(RECORDED_DEM.read_bytes()))
    # the battery was recorded before the unload-reload option existed: its curve added as 3 x the loading E'
    # at the window stresses (the Hardening Soil model's E_ur = 3 E_50, Schanz et al. 1999)
    windows = result["curves"]["cct_modulus_vs_stress"]
    result["curves"]["cct_unload_reload_modulus_vs_stress"] = {
        "normal_stress_pa": windows["normal_stress_pa"],
        "unload_reload_modulus_pa": [3.0 * e for e in windows["confined_modulus_pa"]]}
    job_id = _insert_job(service, status="succeeded", test="battery", spec=result.pop("spec"), result=result,
                         engine_version=result["provenance"]["engine_version"], wall_time_s=result["provenance"]["wall_time_s"])
    open_view(page, service, f"#/jobs/{job_id}")
    expect_text(page, "h2 .status", "succeeded")
    expected = {
        "Fill: settling": ("time (s)", "kinetic energy ratio (-)"),
        "CCT: stress-strain loops": ("normal strain (-)", "normal stress (kPa)"),
        "CCT: confined modulus E' per cycle": ("cycle", "E' (MPa)"),
        "CCT: E' per stress window": ("normal stress (kPa)", "E' (MPa)"),
        "CCT: unload-reload modulus against stress": ("normal stress (kPa)", "modulus (MPa)"),
        "DST: shear stress": ("shear displacement (mm)", "shear stress (kPa)"),
        "DST: lid rise (dilation)": ("shear displacement (mm)", "lid rise (mm)"),
        "DST: Mohr-Coulomb envelope": ("normal stress (kPa)", "shear stress (kPa)"),
        "Angle of repose: heap profile per sector": ("radius (mm)", "surface height (mm)"),
    }
    for title, (x_name, y_name) in expected.items():
        box = page.locator(f".charts [aria-label=\"{title}\"]")
        expect_text(page, f".charts [aria-label=\"{title}\"]", re.escape(x_name))
        text = box.inner_text()
        assert y_name in text, (title, text)
    loops = page.locator(".charts [aria-label='CCT: stress-strain loops']").inner_text()
    assert "cycle 1" in loops and "cycle 2" in loops
    moduli = page.locator(".charts [aria-label='CCT: unload-reload modulus against stress']").inner_text()
    assert "E_ur (unload-reload)" in moduli and "E' (loading, per window)" in moduli
    # drawn by its own view, not also by the fallback that charts unknown curves column by column
    assert page.locator(".charts [aria-label^='cct_unload_reload_modulus_vs_stress']").count() == 0
    dst = page.locator(".charts [aria-label='DST: shear stress']").inner_text()
    assert len(re.findall(r"σn [\d.]+ kPa", dst)) == 4
    page.locator(".charts").screenshot(path=str(shots / "job-dem-curves.png"))


def test_failed_job_shows_one_line_not_a_traceback(page, service):
    """A job row as an older worker left it (message then traceback): the page shows the message only."""
    error = ("ValueError: particle_radius_m too large for the container\n"
             'Traceback (most recent call last):\n  File "/srv/demcal/engine/lab/run.py", line 12, in run\n'
             "    raise ValueError(...)\n")
    job_id = _insert_job(service, status="failed", test="fill", spec={"test": "fill"}, error=error)
    open_view(page, service, f"#/jobs/{job_id}")
    expect_text(page, ".job-error", "Failed: ValueError: particle_radius_m too large for the container")
    body = page.locator("main").inner_text()
    assert "Traceback" not in body and "/srv/demcal" not in body and "raise ValueError" not in body


def test_bad_field_is_shown_beside_its_input(page, service, shots):
    page.watch.allowed.append("status of 422")  # the browser logs the API's refusal; it is the point here
    open_view(page, service, "#/submit")
    form = page.locator("form#submit-job")
    form.locator("select[name=evaluator]").select_option("analytic")  # were it accepted, no DEM would run
    form.locator("input[name=seed]").fill("-1")
    form.get_by_role("button", name="Queue job").click()
    expect_text(page, "form#submit-job .field-error", "greater than or equal to 0")
    label = form.locator("label:has(input[name=seed])")
    assert label.locator(".field-error").count() == 1  # inside its label, under the input (since issue 31)
    assert form.locator("input[name=seed]").get_attribute("aria-invalid") == "true"
    assert form.locator(".field-error").count() == 1
    assert page.url.endswith("#/submit")  # nothing was queued

    open_view(page, service, "#/campaigns")
    form = page.locator("form#new-campaign")
    form.locator("input[name=factor_low]").first.fill("3000")  # above its high of 2700
    form.get_by_role("button", name="Create (draft)").click()
    row = form.locator(".row[data-loc='factors.0']")
    expect_text(page, "form#new-campaign .field-error", "low .* must be below high")
    assert "field-error" in row.locator("xpath=following-sibling::*[1]").get_attribute("class")
    assert page.url.endswith("#/campaigns")  # nothing was created
    row.scroll_into_view_if_needed()
    page.screenshot(path=str(shots / "form-field-error.png"))


def test_error_is_drawn_under_its_own_field(page, service, shots):
    """friction_pp's refusal inside friction_pp's label, under its input; none at the other fields.
    (Placed after the label, it wrapped to the next line, under particle_density_kg_m3.)"""
    page.watch.allowed.append("status of 422")
    open_view(page, service, "#/submit")
    form = page.locator("form#submit-job")
    form.locator("select[name=evaluator]").select_option("analytic")
    form.locator("input[name=friction_pp]").fill("-1")
    form.get_by_role("button", name="Queue job").click()
    label = form.locator("label:has(> input[name=friction_pp])")
    expect_text(page, "form#submit-job label:has(> input[name=friction_pp]) .field-error", "greater than or equal to 0")
    assert form.locator(".field-error").count() == 1
    assert form.locator("label:has(> input[name=particle_density_kg_m3]) .field-error").count() == 0
    box, message = form.locator("input[name=friction_pp]").bounding_box(), label.locator(".field-error").bounding_box()
    assert message["y"] >= box["y"] + box["height"] - 1 and abs(message["x"] - box["x"]) < 8, (box, message)
    assert page.evaluate("document.activeElement.name") == "friction_pp"
    label.screenshot(path=str(shots / "form-error-under-field.png"))


def in_viewport(locator) -> bool:
    return locator.evaluate("""(el) => { const r = el.getBoundingClientRect();
        return r.top >= 0 && r.bottom <= window.innerHeight && r.left >= 0 && r.right <= window.innerWidth; }""")


def test_create_scrolls_to_and_focuses_the_first_field_in_error(page, service, shots):
    """"Create (draft)" sits at the bottom of a long form: after a refusal the page brings the first
    field in error (in the form's order) into view and focuses it, instead of staying at the button."""
    page.watch.allowed.append("status of 422")
    open_view(page, service, "#/campaigns")
    form = page.locator("form#new-campaign")
    form.locator("input[name=seed]").fill("-1")  # near the top
    form.locator("input[name=factor_low]").first.fill("3000")  # further down, above its high of 2700
    button = form.get_by_role("button", name="Create (draft)")
    button.scroll_into_view_if_needed()
    seed = form.locator("input[name=seed]")
    assert not in_viewport(seed)  # the form is longer than the window: the test can fail
    button.click()
    expect_text(page, "form#new-campaign label:has(> input[name=seed]) .field-error", "greater than or equal to 0")
    assert form.locator(".field-error").count() == 2  # the factor row's error too
    from playwright.sync_api import expect

    expect(seed).to_be_focused()
    assert in_viewport(seed) and in_viewport(form.locator("label:has(> input[name=seed]) .field-error"))
    assert page.url.endswith("#/campaigns")  # nothing was created
    page.screenshot(path=str(shots / "form-scrolled-to-error.png"))


def test_decimal_comma_is_one_value_and_ambiguity_is_refused(page, service, shots):
    """ "1397,8" typed as replicate values is one value 1397.8 (not replicates 1397 and 8); "1,397" could
    be 1397 or 1.397 and is refused beside the field, with nothing stored; a job's DST stresses and its
    single numbers follow the same rule."""
    material = service.api("POST", "/materials", json={"name": "decimal comma"}).json()
    open_view(page, service, f"#/materials/{material['id']}")
    # the page's rule is the CLI's: numbers.js on the cases service/materials/replicates.py is tested on
    cases = json.loads((Path(__file__).parent / "data" / "number_lists.json").read_text())
    parsed = page.evaluate("""async (cases) => {
        const { parseNumberList } = await import("/static/js/numbers.js");
        return { read: cases.read.map(([text]) => parseNumberList(text).values),
                 refused: cases.refused.map((text) => parseNumberList(text).error) }; }""", cases)
    for (text, values), got in zip(cases["read"], parsed["read"]):
        assert got == pytest.approx(values), text
    assert all(parsed["refused"]), [t for t, e in zip(cases["refused"], parsed["refused"]) if not e]
    form = page.locator("form#add-measurement")
    form.locator("select[name=test]").select_option("fill")
    form.locator("select[name=quantity]").select_option("bulk_density_kg_m3")
    form.locator("select[name=unit]").select_option("kg/m3")
    assert "decimal comma" in form.locator("label:has(> input[name=values]) .hint").inner_text()  # the rule, in the hint
    values = form.locator("input[name=values]")
    values.fill("1397,8")
    form.get_by_role("button", name="Add").click()
    expect_text(page, "#flash", "measurement added")
    stored = lambda: service.api("GET", f"/materials/{material['id']}").json()["measurements"]  # noqa: E731
    assert [m["values"] for m in stored()] == [[1397.8]]
    # the page redraws itself with the new measurement: type into the redrawn form, not the one it replaces
    expect_text(page, "main table", "1397.8")

    form = page.locator("form#add-measurement")
    form.locator("input[name=values]").fill("1412; 1,397")
    form.get_by_role("button", name="Add").click()
    expect_text(page, "form#add-measurement label:has(> input[name=values]) .field-error", "could be 1397 or 1.397")
    assert page.evaluate("document.activeElement.name") == "values"
    assert len(stored()) == 1  # nothing sent

    form.locator("select[name=quantity]").select_option("porosity")  # one measurement per quantity and condition
    form.locator("select[name=unit]").select_option("1")
    form.locator("input[name=values]").fill("0,4593; 0,46 0.455")  # separators and decimal marks mixed
    form.get_by_role("button", name="Add").click()
    from playwright.sync_api import expect

    expect(page.locator("main table").first).to_contain_text("porosity", timeout=TIMEOUT_MS)
    assert sorted(m["values"] for m in stored()) == [[0.4593, 0.46, 0.455], [1397.8]]
    page.screenshot(path=str(shots / "material-decimal-comma.png"))

    # a confined modulus typed as Pa where kPa was meant: stored (it is physically possible), with the page
    # saying which unit it was likely meant in (granular packings: 1 MPa to 1 GPa, docs/lab.md)
    form = page.locator("form#add-measurement")
    form.locator("select[name=test]").select_option("cct")
    form.locator("select[name=quantity]").select_option("confined_modulus_pa")
    form.locator("select[name=unit]").select_option("Pa")
    form.locator("input[name=values]").fill("8690")
    form.get_by_role("button", name="Add").click()
    expect_text(page, "#flash .warning", "kPa")

    open_view(page, service, "#/submit")
    job = page.locator("form#submit-job")
    job.locator("select[name=evaluator]").select_option("analytic")
    job.locator("input[name=dst_kpa]").fill("6,12,24")  # a comma list without spaces: separators or decimals?
    job.get_by_role("button", name="Queue job").click()
    expect_text(page, "form#submit-job label:has(> input[name=dst_kpa]) .field-error", "more than one comma")
    job.locator("input[name=dst_kpa]").fill("12,5 24")
    friction = job.locator("input[name=friction_pp]")  # one number by the same rule (a number box dropped the comma: 05)
    friction.fill("")
    friction.press_sequentially("0,5")
    job.get_by_role("button", name="Queue job").click()
    page.wait_for_url(re.compile(r"#/jobs/\d+$"))
    spec = service.api("GET", f"/jobs/{page.url.rsplit('/', 1)[1]}").json()["spec"]
    assert spec["options"]["dst_normal_stresses_pa"] == [12500.0, 24000.0]
    assert spec["parameters"]["friction_pp"] == 0.5


def test_jobs_list_hides_campaign_batteries_by_default(page, service):
    """The list shows the jobs submitted directly; campaign batteries behind the origin filter."""
    direct = service.api("POST", "/jobs", json={"evaluator": "analytic", "test": "fill"}).json()
    battery = service.api("POST", "/jobs", json={"evaluator": "analytic", "test": "fill", "campaign_id": 987650}).json()
    open_view(page, service, "#/jobs")
    expect_text(page, "h2", "Jobs \\(")
    links = lambda: page.locator("main table tbody a[href^='#/jobs/']").all_inner_texts()  # noqa: E731
    assert f"#{direct['id']}" in links() and f"#{battery['id']}" not in links()
    page.locator("select[name=origin]").select_option("campaign")
    page.wait_for_url(re.compile(r"origin=campaign"))
    from playwright.sync_api import expect

    expect(page.locator(f"main table a[href='#/jobs/{battery['id']}']")).to_have_count(1, timeout=TIMEOUT_MS)
    assert f"#{direct['id']}" not in links()


def test_api_docs_work_offline(page, service, shots):
    """Swagger UI and ReDoc from the service's own files; every other request is aborted (and fails)."""
    page.goto(f"{service.base_url}/api/v1/docs")
    page.locator(".opblock").first.wait_for()
    assert page.locator(".opblock").count() >= 30
    expect_text(page, "#swagger-ui", "/api/v1/campaigns/\\{campaign_id\\}/diagnosis")
    page.screenshot(path=str(shots / "api-docs.png"))
    page.goto(f"{service.base_url}/api/v1/redoc")
    expect_text(page, "redoc", "Create a campaign \\(draft\\) for a material")
    page.screenshot(path=str(shots / "api-redoc.png"))


def test_missing_pages_say_so_and_clear_the_previous_one(page, service):
    page.watch.allowed.append("status of 404")  # the API's answer for the missing campaign
    open_view(page, service, "#/jobs")
    expect_text(page, "h2", "Jobs \\(")
    page.evaluate("location.hash = '#/no/such/page'")
    expect_text(page, "h2", "Not found")
    assert "There is no page /no/such/page" in page.locator("main").inner_text()
    assert page.locator("h2", has_text="Jobs (").count() == 0
    page.evaluate("location.hash = '#/campaigns/987654'")
    expect_text(page, "main", "987654")
    expect_text(page, "h2", "Not found")


def test_unload_reload_targets_are_drawn_beside_the_model_on_the_stiffness_panel(page, service, shots):
    """A material measured for its unload-reload modulus at two stresses: the campaign's "Across conditions" panel
    draws E_ur measured and modelled on the log-log stiffness axes (where the contact law shows). The measurements:
    the thesis aggregate's E' 8.69 MPa (Table 4.5) times the Hardening Soil model's E_ur / E_50 = 3, growing as
    sigma^0.5 from 30 kPa (Schanz et al. 1999's sands)."""
    import time

    from conftest_s2 import campaign_body

    stresses = [10.0e3, 30.0e3]
    materials = service.api("GET", "/materials", params={"limit": 200}).json()["items"]
    thesis = next(m for m in materials if m["name"] == "thesis-coarse-aggregate")
    copy = service.api("POST", f"/materials/{thesis['id']}/copy", json={"name": "aggregate with E_ur"}).json()
    for stress in stresses:
        modulus = 3.0 * 8.69e6 * (stress / 30.0e3) ** 0.5
        assert service.api("POST", f"/materials/{copy['id']}/measurements", json={
            "test": "cct", "quantity": "unload_reload_modulus_pa", "values": [modulus], "unit": "Pa",
            "condition": {"normal_stress_pa": stress}}).status_code == 201
    body = campaign_body(copy["id"], name="unload-reload")
    body["targets"] += [{"test": "cct", "quantity": "unload_reload_modulus_pa", "condition": {"normal_stress_pa": s}}
                        for s in stresses]
    cid = service.api("POST", "/campaigns", json=body).json()["id"]
    assert service.api("POST", f"/campaigns/{cid}/start").status_code < 300
    deadline = time.monotonic() + TIMEOUT_MS / 1000
    while service.api("GET", f"/campaigns/{cid}").json()["status"] != "completed":
        assert time.monotonic() < deadline, "the campaign did not complete"
        time.sleep(0.5)
    open_view(page, service, f"#/campaigns/{cid}")
    panel = "[aria-label='modulus against stress']"
    expect_text(page, panel, "Stiffness: E_ur against σn \\(log-log\\)")
    text = page.locator(panel).inner_text()
    assert "E_ur measured" in text and "E_ur model" in text and "modulus (MPa)" in text, text
    section_shot(page, shots, "Across conditions", "campaign-conditions-unload-reload")


def test_no_physical_match_page_offers_no_add_button(page, service, shots):
    """Issue 33: under "Diagnosis: no physical match" the page offered an enabled "Add Hertz ..." button
    for a significant effect. Now the table offers none; only an override, styled apart, that asks for
    confirmation first (dismissed here: nothing is added). The campaign is the API test's (the thesis
    aggregate with an impossible bulk density, tests/service/test_verdict_rules_api.py), made through the API."""
    import time

    from conftest_s2 import campaign_body
    from test_verdict_rules_api import DENSITY_PRIOR, IMPOSSIBLE_BULK_DENSITY

    material = service.api("GET", "/materials", params={"limit": 200}).json()["items"]
    thesis = next(m for m in material if m["name"] == "thesis-coarse-aggregate")
    copy = service.api("POST", f"/materials/{thesis['id']}/copy", json={"name": "impossible density"}).json()
    old = next(m for m in copy["measurements"] if m["test"] == "fill" and m["quantity"] == "bulk_density_kg_m3")
    assert service.api("DELETE", f"/materials/{copy['id']}/measurements/{old['id']}").status_code == 204
    assert service.api("POST", f"/materials/{copy['id']}/measurements", json={
        "test": "fill", "quantity": "bulk_density_kg_m3", "values": IMPOSSIBLE_BULK_DENSITY, "unit": "kg/m3"}).status_code == 201
    cid = service.api("POST", "/campaigns", json=campaign_body(copy["id"], name="no match",
                                                                priors=[DENSITY_PRIOR])).json()["id"]
    assert service.api("POST", f"/campaigns/{cid}/start").status_code < 300
    deadline = time.monotonic() + TIMEOUT_MS / 1000
    while service.api("GET", f"/campaigns/{cid}").json()["status"] != "completed":
        assert time.monotonic() < deadline, "the campaign did not complete"
        time.sleep(0.5)
    open_view(page, service, f"#/campaigns/{cid}")
    expect_text(page, "section.diagnosis h3", "Diagnosis: no physical match")
    assert page.locator("section.diagnosis form.add-effect").count() == 0
    assert page.locator("section.diagnosis button", has_text=re.compile(r"^Add ")).count() == 0
    override = page.locator("section.diagnosis details.override")
    assert override.count() == 1 and override.locator("button.override").count() == 1
    override.locator("summary").click()
    dialogs = []
    page.once("dialog", lambda d: (dialogs.append(d.message), d.dismiss()))
    override.locator("button.override").click()
    assert dialogs and "no physical match" in dialogs[0] and "goes against it" in dialogs[0]
    assert len(service.api("GET", f"/campaigns/{cid}/iterations").json()["items"]) == 1  # dismissed: nothing added
    # what holds and what does not, beside the verdict
    expect_text(page, "section.verdict ul.checks", "targets within reach")
    section_shot(page, shots, "Diagnosis", "campaign-diagnosis-no-match")


def test_a_candidate_its_probe_could_not_judge_is_marked_not_ruled_out(page, service, shots):
    """Session 35: "no misfit" no longer rules out a candidate whose probe was too noisy to say whether these
    measurements would see it (calibration.unseen.undetermined); the table marks it "not ruled out: probe too
    noisy", with its LM range at the plausible top in the title, apart from "unseen". The analytic evaluator's
    probes have no scatter, so the campaign's own diagnosis is served with its unseen Hertz row given the
    probe tier B's weak Hertz world measured (docs/results/tier_b_weak.json: scatter 1.17 of the signature,
    LM 0-259 at the top)."""
    from calibration.unseen import detectable_lm

    cid = thesis_campaign_completed(service, "noisy probe")
    report = service.api("GET", f"/campaigns/{cid}/report", params={"number": 1}).json()
    diagnosis = report["diagnosis"]
    significant = {r["effect"] for r in diagnosis["ranking"] if r["significant"]}
    hertz = next(u for u in diagnosis["unseen"] if u["effect"] == "hertz_mindlin")
    assert "hertz_mindlin" not in significant
    need = detectable_lm(0.05, len(diagnosis["ranking"]))
    noisy = {**{k: hertz[k] for k in ("effect", "title", "power", "measure")}, "lm_needed": need,
             "signature_noise": 1.17, "lm_at_top_low": 0.0, "lm_at_top_high": 259.0}
    served = {**diagnosis, "unseen": [u for u in diagnosis["unseen"] if u["effect"] != "hertz_mindlin"],
              "undetermined": [noisy]}
    # the page reads the diagnosis from the iteration's report
    page.route(re.compile(rf".*/api/v1/campaigns/{cid}/report\?number=1$"),
               lambda route: route.fulfill(json={**report, "diagnosis": served}))
    open_view(page, service, f"#/campaigns/{cid}")
    expect_text(page, "section.diagnosis h3", "Diagnosis: ")
    marker = page.locator("section.diagnosis .undetermined")
    assert marker.count() == 1 and marker.inner_text() == "not ruled out: probe too noisy"
    # core.js fmt: two significant figures for the range, three for the threshold
    assert marker.get_attribute("title") == (f"LM 0-260 at its strongest plausible strength, "
                                             f"{float(f'{need:.3g}'):g} needed")
    row = page.locator("section.diagnosis tr", has=page.locator(".undetermined"))
    assert "hertz_mindlin" in row.inner_text() and row.locator(".unseen").count() == 0
    assert page.locator("section.diagnosis .unseen").count() == len(served["unseen"])
    # an unseen candidate's projection (LM 0 on a signature too short to see) is no strength: none printed
    for effect in (u["effect"] for u in served["unseen"] if u["effect"] not in significant):
        cells = page.locator("section.diagnosis tr", has=page.locator(f"code:text-is('{effect}')")).locator("td")
        assert cells.nth(5).inner_text().strip() == "none (unseen)", cells.nth(5).inner_text()
    section_shot(page, shots, "Diagnosis", "campaign-diagnosis-undetermined")


def test_long_listings_page_with_the_total_and_next_previous_links(page, service):
    """GET /materials answers a page; the list says which rows of how many and links the next page."""
    total = service.api("GET", "/materials", params={"limit": 1}).json()["total"]  # the bundled one, and earlier tests'
    for i in range(51 - total):  # one more than the page's 50 (core.js PAGE_SIZE)
        assert service.api("POST", "/materials", json={"name": f"paged {i:02d}"}).status_code == 201
    open_view(page, service, "#/materials")
    expect_text(page, "h2", "Materials \\(51\\)")
    expect_text(page, "p.pager", "1–50 of 51")
    page.locator("p.pager a", has_text="next").click()
    page.wait_for_url(re.compile(r"#/materials\?offset=50"))
    expect_text(page, "p.pager", "51–51 of 51")
    assert page.locator("main table tbody tr").count() == 1
    page.locator("p.pager a", has_text="previous").click()
    expect_text(page, "p.pager", "1–50 of 51")


def test_a_server_with_tokens_asks_for_one_and_the_page_sends_it(browser, tmp_path):
    """Reads need the token on such a server: the page says where it goes, then lists with it."""
    token = "page-token-0123456789"
    svc = start_service(tmp_path, workers=0, DEMCAL_TOKENS=f"alice:{token}")
    try:
        context = browser.new_context()
        context.set_default_timeout(TIMEOUT_MS)
        pg = context.new_page()
        pg.watch = watch_page(pg, svc.base_url)
        pg.watch.allowed.append("status of 401")  # the browser logs the refused read; it is the point here
        pg.goto(f"{svc.base_url}/#/jobs")
        expect_text(pg, "main", "This server needs a token")
        pg.fill("#token", token)
        pg.locator("#token").dispatch_event("change")
        expect_text(pg, "h2", "Jobs \\(0\\)")
        problems = pg.watch.problems()
        context.close()
        assert not problems, problems
    finally:
        stop_service(svc.proc)


def test_a_polish_for_a_missed_prior_says_why_and_lists_its_anchors(page, service, shots):
    """Session 37: an added effect whose fit misses a measured parameter is polished on the batteries, with slopes
    measured there and two anchors (the surfaces' optimum with the missed parameter held at its measured value,
    and with every measured parameter held). The verdict card says why it polished, where the Jacobian came
    from, and lists each anchor with its chi2 and whether the steps started there. The polish is the library
    loop's in tier A seed 13's Hertz world (tests/service/polish_case.py), served in a real campaign's report."""
    from polish_case import hertz_polish

    polish = hertz_polish()
    assert polish["jacobian"] == "batteries" and len(polish["anchors"]) == 2
    open_report_serving(page, service, "polished", polish=polish)
    expect_text(page, "section.verdict .polish p.muted:not(.holdout)", "Polishing on the batteries: ")
    line = page.locator("section.verdict .polish p.muted:not(.holdout)").inner_text()
    assert f"{polish['steps']} Gauss-Newton step(s), {polish['batteries']} batteries" in line
    assert "Jacobian from the batteries" in line and f"why: {polish['why']}" in line

    def three(value):  # core.js fmt(value, 3)
        return f"{float(f'{value:.3g}'):g}"

    items = page.locator("section.verdict .polish ul.anchors li")
    assert items.count() == len(polish["anchors"])
    for k, anchor in enumerate(polish["anchors"]):
        text = items.nth(k).inner_text()
        held = ", ".join(f"{name} {three(value)}" for name, value in anchor["held"].items())
        assert text.startswith(f"held at the measured {held}: χ² {three(anchor['chi2'])}, "), text
        assert ("the steps started here" in text) == bool(anchor.get("taken")), text
        assert ("taken" in (items.nth(k).get_attribute("class") or "")) == bool(anchor.get("taken"))
        if anchor.get("step_chi2") is not None:  # an anchor not taken gets a step of its own (session 38)
            assert f"; one step from it: χ² {three(anchor['step_chi2'])}, " in text, text
            assert ("the polish went on from there" in text) == bool(anchor.get("step_taken")), text
    assert any(a.get("step_chi2") is not None for a in polish["anchors"])
    # session 41: the polish took steps, so the chosen point ran again at fresh seeds and the report reads those
    assert len(polish["holdout_seeds"]) == 2 and polish["holdout_seeds"] != polish["seeds"]
    held = page.locator("section.verdict .polish p.holdout").inner_text()
    assert held.startswith(f"Held out: the chosen point again at 2 fresh seed(s), χ² {three(polish['holdout_chi2'])}; "), held
    assert "the report reads these batteries, on which no step was chosen" in held
    section_shot(page, shots, "Verdict", "campaign-polish-anchors")


def test_the_report_shows_each_parameter_s_interval_the_trade_and_an_interval_widened(page, service, shots):
    """Issue 33 item 3: the page shows each calibrated parameter with its interval, says which pair trades rather
    than letting one optimum stand as known, and marks an interval that points measured on the batteries widened,
    with the surfaces' interval it replaced (session 39). The intervals are the library loop's in tier A seed 11's
    rolling world (tests/service/intervals_case.py), served in a real campaign's report."""
    from intervals_case import trading_intervals

    intervals = trading_intervals()
    open_report_serving(page, service, "intervals", intervals=intervals)
    expect_text(page, "section.parameters h3", "Parameters: optimum and 95 % interval")

    def four(value):  # core.js fmt(value): four significant digits, exponent from 1e5
        return f"{value:.3e}".replace("e+0", "e+") if abs(value) >= 1e5 else f"{float(f'{value:.4g}'):g}"

    for name, row in intervals["parameters"].items():
        cell = page.locator(f'section.parameters span.interval[data-parameter="{name}"]')
        assert cell.inner_text() == f"{four(row['low'])} – {four(row['high'])}", name
    trades = page.locator("section.parameters p.trade")
    assert trades.count() == len(intervals["trades"])
    assert trades.first.inner_text() == intervals["trades"][0]["message"]
    (name,) = intervals["measured_points"]["widened"]
    wald = intervals["parameters"][name]["wald"]
    note = page.locator("section.parameters tr", has=page.locator(f'span.interval[data-parameter="{name}"]'))
    assert (f"widened to the points measured on the batteries (the surfaces' alone: {four(wald['low'])} – "
            f"{four(wald['high'])})") in note.inner_text()
    section_shot(page, shots, "Parameters", "campaign-parameter-intervals")
