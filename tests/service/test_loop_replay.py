"""One loop: a campaign's stored batteries, replayed through the notebook loop, give the verdicts the
service stored.

The service's runner and ``calibration.loop`` both drive ``calibration.machine``; nothing but the
storage differs. So the same batteries must give, iteration by iteration, the same verdict, the same
optimum (to rounding: relative 1e-9), the same diagnosis ranking, the same added effect and the same
stop reason. The campaign is the automatic loop on the bundled thesis aggregate with the closed-form
stand-in, whose spheres miss the aggregate's friction angle (a strength deficit the loop must name).
"""
from conftest_s2 import API, campaign_body, run_to_end, s2, thesis_material_id  # noqa: F401

from calibration import fits
from calibration.keys import select
from calibration.loop import CalibrationLoop
from calibration.records import Measured
from calibration.replay import ReplayEvaluator, differences
from calibration.settings import LoopSettings
from service.materials.store import get_material


def _targets(app, material_id: int) -> list[Measured]:
    with app.state.session_factory() as session:
        return [Measured.from_record(m) for m in select(get_material(session, material_id).measurements, None)]


def test_the_notebook_loop_replays_an_automatic_campaign_to_the_same_answers(s2):
    client, app, settings = s2
    material_id = thesis_material_id(client)
    body = campaign_body(material_id, targets=None, automatic=True, max_iterations=3)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    fits.forget()
    assert run_to_end(client, app, settings, cid, max_rounds=60)["status"] == "completed"
    stored = client.get(f"{API}/campaigns/{cid}/iterations").json()["items"]
    assert len(stored) >= 2 and stored[0]["report"].get("diagnosis")  # the loop diagnosed and added an effect
    targets = _targets(app, material_id)
    # the surfaces are fitted once per iteration and compared target (each measurement once: a porosity is the
    # bulk density's), though analysis, every polishing round, the report and the diagnosis all use them
    compared = len(targets) - len(stored[0]["report"].get("left_out_targets") or [])
    assert compared < len(targets)
    assert fits.FIT_COUNT["surfaces"] == len(stored) * compared

    fits.forget()
    evaluator = ReplayEvaluator(stored)
    loop_settings = LoopSettings.model_validate({k: v for k, v in body.items() if k in LoopSettings.model_fields})
    replayed = CalibrationLoop(targets, evaluator, loop_settings).run()
    assert differences(stored, replayed.iterations) == []
    assert fits.FIT_COUNT["surfaces"] == len(stored) * compared
    # every stored battery was asked for once, and no other; a battery an iteration reused from an earlier
    # one (calibration.reuse) is not asked for again, by the service or the notebook loop
    reused = [r for it in stored for r in it["runs"] if r["reused_from"]]
    assert reused and all(r["status"] == "succeeded" for r in reused)
    assert evaluator.runs == sum(len(it["runs"]) for it in stored) - len(reused)
    # a reused run is the earlier battery itself: its job and seed
    earlier = {(r["job_id"], r["seed"]) for it in stored[:1] for r in it["runs"]}
    assert {(r["job_id"], r["seed"]) for r in stored[1]["runs"] if r["reused_from"]} <= earlier
