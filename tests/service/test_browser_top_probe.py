"""The diagnosis panel of a candidate probed twice (issue 33): at its secant step and at its plausible top
(calibration.attribute.top_probes). The ranking's Explained cell shows the share read and each probe's, with the
strength each ran at, so a user sees the response bend with strength."""
from __future__ import annotations

from sqlalchemy import create_engine, update
from sqlalchemy.orm import Session

from test_browser import browser, expect_text, open_view, page, pytestmark, section_shot, service, shots  # noqa: F401
from test_browser_alias import _with_ids


def _twice_probed_loop(monkeypatch):
    """The stand-in's cohesion 150 J/m2 (seed 7), its diagnosis made to probe cohesion at its top as well (the
    rule's own cases are tests/calibration/test_top_probe.py)."""
    from calibration import attribute
    from calibration.conditions import standin_conditions
    from calibration.evaluators import StandinEvaluator
    from calibration.loop import CalibrationLoop
    from calibration.testbed import OPTIONS, loop_settings, make_case

    monkeypatch.setattr(attribute, "top_probes",
                        lambda diagnosis, probed=frozenset(): [] if probed else ["cohesion_adhesive"])
    case = make_case(7, "single", effects={"cohesion_adhesive": 150.0})
    settings = loop_settings(case, diagnose_always=True, automatic=False)
    return CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), settings).run()


def test_the_ranking_shows_both_probes_of_a_candidate_probed_at_its_top(page, service, shots, monkeypatch):
    from conftest_s2 import campaign_body
    from service.models.campaign import Campaign, CampaignIteration

    result = _twice_probed_loop(monkeypatch)
    it = result.first
    row = next(r for r in it.report["diagnosis"]["ranking"] if r["effect"] == "cohesion_adhesive")
    assert {p["strength_probed"] for p in row["probes"]} == {60.0, 200.0}
    material = service.api("GET", "/materials", params={"limit": 200}).json()["items"]
    thesis = next(m for m in material if m["name"] == "thesis-coarse-aggregate")
    cid = service.api("POST", "/campaigns", json=campaign_body(thesis["id"], name="probed twice")).json()["id"]
    engine = create_engine(service.database_url)
    with Session(engine) as session:
        session.add(CampaignIteration(campaign_id=cid, number=1, phase="done", parameters=it.parameters,
                                      design=it.design, models=it.models, optimum=it.optimum,
                                      confirmation=it.confirmation, report=_with_ids(it.report)))
        session.execute(update(Campaign).where(Campaign.id == cid).values(status="completed", current_iteration=1))
        session.commit()
    engine.dispose()
    served = service.api("GET", f"/campaigns/{cid}/diagnosis").json()
    served_row = next(r for r in served["ranking"] if r["effect"] == "cohesion_adhesive")
    assert [p["probe"] for p in served_row["probes"]] == [p["probe"] for p in row["probes"]]
    open_view(page, service, f"#/campaigns/{cid}")
    expect_text(page, "section.diagnosis h3", "Diagnosis: ")
    expect_text(page, "section.diagnosis .probes", r"at 60 J/m2.*at 200 J/m2")
    section_shot(page, shots, "Diagnosis", "campaign-diagnosis-top-probe")
