"""POST /campaigns/{id}/continue: a completed automatic campaign taken up again with more iterations.

On the bundled thesis aggregate with the analytic stand-in (spheres that saturate near 36 deg against the
measured 60.6 deg: a strength deficit rolling resistance or particle shape supplies), a limit of one
iteration stops the loop with an effect indicated; continuing runs the iteration that adds it, and the
error falls. A campaign that stopped for its answer, a draft, or a limit beyond ten is refused, naming why,
and leaves the stored campaign as it was."""
import pytest

from conftest_s2 import API, campaign_body, error_loc, run_to_end, s2, thesis_material_id  # noqa: F401

from calibration.settings import MAX_ITERATIONS
from calibration.vocabulary import StopReason

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)


def _stored(client, cid: int) -> tuple[dict, list]:
    summary = client.get(f"{API}/campaigns/{cid}").json()
    items = client.get(f"{API}/campaigns/{cid}/iterations").json()["items"]
    return summary, [(it["number"], it["phase"], (it["report"] or {}).get("automatic")) for it in items]


def test_a_campaign_stopped_by_its_limit_continues_and_the_error_falls(s2):
    client, app, settings = s2
    body = campaign_body(thesis_material_id(client), targets=None, automatic=True, max_iterations=1)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]

    draft = client.post(f"{API}/campaigns/{cid}/continue", json={"more_iterations": 1})
    assert draft.status_code == 409 and error_loc(draft) == ["path", "campaign_id"], draft.text

    client.post(f"{API}/campaigns/{cid}/start")
    summary = run_to_end(client, app, settings, cid)
    assert summary["status"] == "completed" and summary["stop_reason"] == StopReason.MAX_ITERATIONS
    assert summary["continuable"] is True
    indicated = client.get(f"{API}/campaigns/{cid}/diagnosis").json()["indicated"]
    assert indicated and indicated[0] in ("rolling_epsd2", "particle_shape")

    before = _stored(client, cid)
    for more in (0, MAX_ITERATIONS):  # refused by the body's bounds: 422 naming the field, nothing stored
        bad = client.post(f"{API}/campaigns/{cid}/continue", json={"more_iterations": more})
        assert bad.status_code == 422 and error_loc(bad) == ["body", "more_iterations"], bad.text
    assert _stored(client, cid) == before

    going = client.post(f"{API}/campaigns/{cid}/continue", json={"more_iterations": 1})
    assert going.status_code == 200, going.text
    assert going.json()["status"] == "running" and going.json()["stop_reason"] is None
    assert run_to_end(client, app, settings, cid, max_rounds=40)["status"] == "completed"

    history = client.get(f"{API}/campaigns/{cid}/history").json()["iterations"]
    first, second = history
    assert first["effect_added_next"] == [indicated[0]] and first["continued"] == {
        "more_iterations": 1, "max_iterations": 2, "stopped_for": StopReason.MAX_ITERATIONS}
    assert second["effects"] == [indicated[0]] and second["decision"]["accepted"]
    assert second["chi2"] < first["chi2"] and second["weighted_rms"] < first["weighted_rms"]
    assert client.get(f"{API}/campaigns/{cid}/iterations/2").json()["parameters"]["factors"][-1]["name"].endswith(
        ("rolling_friction", "aspect_ratio"))


def test_a_campaign_that_stopped_for_its_answer_is_refused_and_left_as_it_was(s2):
    client, app, settings = s2
    # the thesis's three calibrated targets against three free parameters: the loop ends matching them with no
    # degrees of freedom left to test (or passing, were any left): an answer, not the limit
    body = campaign_body(thesis_material_id(client), automatic=True, max_iterations=3)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    summary = run_to_end(client, app, settings, cid)
    assert summary["status"] == "completed" and summary["stop_reason"].startswith(
        (StopReason.PASSES, StopReason.UNTESTABLE)), summary
    assert summary["continuable"] is False
    before = _stored(client, cid)
    refused = client.post(f"{API}/campaigns/{cid}/continue")
    assert refused.status_code == 409 and error_loc(refused) == ["body", "more_iterations"], refused.text
    assert "more iterations do not change" in refused.json()["detail"][0]["msg"]
    assert _stored(client, cid) == before

    missing = client.post(f"{API}/campaigns/999999/continue")
    assert missing.status_code == 404


def test_a_failed_campaign_is_retried_where_it_failed_keeping_its_batteries(s2):
    """A battery of the design fails (its job marked failed as a worker's exception leaves it): the campaign fails
    naming it; POST .../retry queues that battery's job again, keeps the others, and the campaign completes with
    the same runs. Retrying a campaign that did not fail is a 409."""
    from sqlalchemy import select, update

    from service.campaigns.runner import CampaignRunner
    from service.models.campaign import CampaignRun
    from service.models.job import Job

    client, app, settings = s2
    body = campaign_body(thesis_material_id(client))
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    refused = client.post(f"{API}/campaigns/{cid}/retry")
    assert refused.status_code == 409 and error_loc(refused) == ["path", "campaign_id"]
    client.post(f"{API}/campaigns/{cid}/start")
    CampaignRunner(app.state.session_factory, settings).tick()  # the design's batteries queued
    with app.state.session_factory() as session:
        job_ids = sorted(session.scalars(select(CampaignRun.job_id).where(CampaignRun.job_id.is_not(None))))
        assert len(job_ids) >= 8
        broken = job_ids[3]
        session.execute(update(Job).where(Job.id == broken).values(status="failed", error="ZeroDivisionError: float "
                                                                    "division by zero", attempts=1))
        session.commit()
    failed = run_to_end(client, app, settings, cid)
    assert failed["status"] == "failed" and f"(job {broken}) failed: ZeroDivisionError" in failed["error"]

    retried = client.post(f"{API}/campaigns/{cid}/retry")
    assert retried.status_code == 200, retried.text
    assert retried.json()["status"] == "running" and retried.json()["error"] is None
    done = run_to_end(client, app, settings, cid)
    assert done["status"] == "completed", done
    runs = client.get(f"{API}/campaigns/{cid}/iterations/1").json()["runs"]
    assert sorted(r["job_id"] for r in runs if r["kind"] == "design") == job_ids  # the same batteries, none twice
    assert all(r["status"] == "succeeded" for r in runs)
    assert client.get(f"{API}/jobs/{broken}").json()["status"] == "succeeded"
    assert client.post(f"{API}/campaigns/{cid}/retry").status_code == 409
