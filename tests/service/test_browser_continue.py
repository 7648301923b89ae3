"""A completed automatic campaign taken up again from its page: the loop stopped at its one-iteration limit
with an effect indicated (the stand-in spheres cannot reach the aggregate's 60.6 deg); "Continue with one
more iteration" runs the iteration that adds it, the history shows the error fall, and the button is gone
once the loop stops for its answer or its new limit."""
from __future__ import annotations

from test_browser import browser, expect_text, open_view, page, pytestmark, section_shot, service, shots  # noqa: F401


def test_a_campaign_stopped_at_its_limit_continues_from_its_page(page, service, shots):
    from conftest_s2 import campaign_body

    material = service.api("GET", "/materials", params={"limit": 200}).json()["items"]
    thesis = next(m for m in material if m["name"] == "thesis-coarse-aggregate")
    body = campaign_body(thesis["id"], name="stopped at its limit", targets=None, automatic=True, max_iterations=1)
    cid = service.api("POST", "/campaigns", json=body).json()["id"]
    service.api("POST", f"/campaigns/{cid}/start")
    open_view(page, service, f"#/campaigns/{cid}")
    expect_text(page, "h2 .status", "completed")
    expect_text(page, "p.stop-reason", "maximum number of iterations reached")
    indicated = service.api("GET", f"/campaigns/{cid}/diagnosis").json()["indicated"][0]
    button = page.locator("p.stop-reason button[data-action=continue]")
    assert button.inner_text() == "Continue with one more iteration"
    page.locator("p.stop-reason").screenshot(path=str(shots / "campaign-continue.png"))

    button.click()
    expect_text(page, "nav.iterations", f"2 · {indicated}")
    expect_text(page, "h2 .status", "completed")
    expect_text(page, "section.history .chi2dof[data-iteration='2']", r"\d")
    chi2 = {n: float(page.locator(f"section.history .chi2dof[data-iteration='{n}']").inner_text()) for n in (1, 2)}
    assert chi2[2] < chi2[1], chi2
    summary = service.api("GET", f"/campaigns/{cid}").json()
    # a second limit reached shows the button again; any other stop (its answer) does not
    assert page.locator("p.stop-reason button[data-action=continue]").count() == int(summary["continuable"])
    history = service.api("GET", f"/campaigns/{cid}/history").json()["iterations"]
    assert history[0]["continued"]["stopped_for"] == "maximum number of iterations reached"
    expect_text(page, "section.history .continued", r"continued \(limit 2; had stopped: maximum number of iterations reached\)")
    section_shot(page, shots, "Across iterations", "campaign-continued-history")
