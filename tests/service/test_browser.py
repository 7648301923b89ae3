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
    assert "friction_angle_deg" in " ".join(failing.all_inner_texts())
    assert page.locator("section.verdict").count() == 1 and page.get_by_text("Verdict:").count() == 1  # printed once
    # the ranking chart and table name the effect; the first significant one can be added
    expect_text(page, "section.diagnosis h3", "Diagnosis: ")
    add = page.locator("section.diagnosis form.add-effect").first
    top = add.get_attribute("data-effect")
    assert top in ("rolling_epsd2", "particle_shape"), top
    assert page.locator("section.diagnosis [aria-label='effect ranking'] svg").count() == 1
    expect_text(page, "section.history .chi2dof[data-iteration='1']", r"\d")
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
    # iteration 1 stays readable from the selector
    page.locator("nav.iterations a", has_text=re.compile(r"^1")).click()
    expect_text(page, "p.active-effects", "Iteration 1 model: no contact effects")
    page.screenshot(path=str(shots / "campaign-iteration-1.png"))


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
    job_id = _insert_job(service, status="succeeded", test="battery", spec=result.pop("spec"), result=result,
                         engine_version=result["provenance"]["engine_version"], wall_time_s=result["provenance"]["wall_time_s"])
    open_view(page, service, f"#/jobs/{job_id}")
    expect_text(page, "h2 .status", "succeeded")
    expected = {
        "Fill: settling": ("time (s)", "kinetic energy ratio (-)"),
        "CCT: stress-strain loops": ("normal strain (-)", "normal stress (kPa)"),
        "CCT: confined modulus E' per cycle": ("cycle", "E' (MPa)"),
        "CCT: E' per stress window": ("normal stress (kPa)", "E' (MPa)"),
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
    assert "field-error" in label.locator("xpath=following-sibling::*[1]").get_attribute("class")
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
