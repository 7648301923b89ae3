"""The campaign page after an alias refit (issue 33): the automatic mode kept an effect, fitted its alias in its
place and compared the two; the page says which iteration's model is the answer, beside the stop reason, and the
history's Automatic column marks it."""
from __future__ import annotations

from sqlalchemy import create_engine, update
from sqlalchemy.orm import Session

from test_browser import browser, expect_text, open_view, page, pytestmark, section_shot, service, shots  # noqa: F401


def _refitted_loop():
    """The test bed's elongation 1.8 (seed 8): elongation and rolling resistance in one alias group, elongation
    added, rolling resistance fitted in its place, elongation kept (tests/calibration/test_verdict_rules.py)."""
    from calibration.conditions import standin_conditions
    from calibration.evaluators import StandinEvaluator
    from calibration.loop import CalibrationLoop
    from calibration.testbed import OPTIONS, loop_settings, make_case

    case = make_case(8, "single", effects={"particle_shape": 1.8})
    return CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), loop_settings(case)).run()


def _with_ids(record: dict | None) -> dict | None:
    """A notebook loop's targets carry no measurement ids (no database); the service's answers require one."""
    if not record:
        return record
    ids = {}
    for row in record.get("targets") or []:
        row["measurement_id"] = ids.setdefault((row["test"], row["quantity"], str(row.get("condition"))), len(ids) + 1)
    return record


def test_the_page_names_the_model_kept_after_an_alias_refit(page, service, shots):
    from conftest_s2 import campaign_body
    from service.models.campaign import Campaign, CampaignIteration

    result = _refitted_loop()
    kept = result.final.number
    assert kept < result.iterations[-1].number  # the refit's iteration is not the answer
    material = service.api("GET", "/materials", params={"limit": 200}).json()["items"]
    thesis = next(m for m in material if m["name"] == "thesis-coarse-aggregate")
    cid = service.api("POST", "/campaigns", json=campaign_body(thesis["id"], name="alias refit")).json()["id"]
    # the notebook loop's iterations stored as the campaign's (one loop, calibration.machine): a finished campaign
    engine = create_engine(service.database_url)
    with Session(engine) as session:
        for it in result.iterations:
            session.add(CampaignIteration(campaign_id=cid, number=it.number, phase="done", parameters=it.parameters,
                                          design=it.design, models=it.models, optimum=it.optimum,
                                          confirmation=it.confirmation, report=_with_ids(it.report)))
        session.execute(update(Campaign).where(Campaign.id == cid).values(
            status="completed", current_iteration=result.iterations[-1].number))
        session.commit()
    engine.dispose()
    summary = service.api("GET", f"/campaigns/{cid}").json()
    assert summary["kept_iteration"] == kept
    open_view(page, service, f"#/campaigns/{cid}")
    expect_text(page, "p.stop-reason", "particle_shape kept")
    expect_text(page, "p.kept-iteration", f"iteration {kept}'s")
    expect_text(page, "section.history", f"model kept: iteration {kept}")
    section_shot(page, shots, "Across iterations", "campaign-history-alias-refit")

