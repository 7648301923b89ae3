"""A failed campaign run on from its page: "Retry" queues its failed batteries again and the campaign completes."""
from __future__ import annotations

from sqlalchemy import create_engine, update
from sqlalchemy.orm import Session

from test_browser import browser, expect_text, open_view, page, pytestmark, service, shots  # noqa: F401


def test_a_failed_campaign_is_retried_from_its_page(page, service, shots):
    from conftest_s2 import campaign_body
    from service.models.campaign import Campaign

    material = service.api("GET", "/materials", params={"limit": 200}).json()["items"]
    thesis = next(m for m in material if m["name"] == "thesis-coarse-aggregate")
    cid = service.api("POST", "/campaigns", json=campaign_body(thesis["id"], name="failed once")).json()["id"]
    engine = create_engine(service.database_url)
    with Session(engine) as session:  # as the runner leaves a campaign whose battery failed before it started one
        session.execute(update(Campaign).where(Campaign.id == cid).values(
            status="failed", error="design run 7 (job 85) failed: ZeroDivisionError: float division by zero"))
        session.commit()
    engine.dispose()
    open_view(page, service, f"#/campaigns/{cid}")
    expect_text(page, "h2 .status", "failed")
    expect_text(page, "p.job-error", "ZeroDivisionError")
    page.screenshot(path=str(shots / "campaign-failed-retry.png"))
    page.locator("button[data-action=Retry]").click()
    expect_text(page, "h2 .status", "completed")
    assert page.locator("button[data-action=Retry]").count() == 0 and page.locator("p.job-error").count() == 0
    assert service.api("GET", f"/campaigns/{cid}").json()["error"] is None
