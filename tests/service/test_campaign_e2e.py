"""A whole campaign with the analytic evaluator, from creation to report, through the API."""
from __future__ import annotations

import math

import pytest

from conftest_s2 import API, campaign_body, run_to_end, s2, thesis_material_id  # noqa: F401
from calibration.attribute import signature_seeds
from engine.candidates import candidates
from service.models.job import Job

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)


def test_analytic_campaign_from_creation_to_report(s2):
    client, app, settings = s2
    # every phase at its fullest: polishing always, its Jacobian on the batteries, the diagnosis at every seed
    body = campaign_body(thesis_material_id(client), polish_when="always", polish_jacobian="batteries",
                         adaptive_replicates=False)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    final = run_to_end(client, app, settings, cid)
    assert final["status"] == "completed", final["error"]

    # 2^3 factorial + 3 centre replicates, one battery each, plus a confirmation battery per seed (2 by default)
    (iteration,) = client.get(f"{API}/campaigns/{cid}/iterations").json()["items"]
    runs = iteration["runs"]
    design_runs = [r for r in runs if r["kind"] == "design"]
    assert len(design_runs) == 11 and sum(r["is_centre"] for r in design_runs) == 3
    own = [r for r in runs if r["kind"] in ("design", "confirmation")]
    assert len({r["seed"] for r in own}) == len(own)  # centre replicates (and confirmation) use distinct seeds
    confirmation_seeds = {r["seed"] for r in runs if r["kind"] == "confirmation"}
    assert len(confirmation_seeds) == 2
    # polishing on the batteries: one Jacobian point per factor, then one trial point per round (full
    # length, then shorter only if it failed), every point at the confirmation's seeds (common random numbers)
    # after a step, the chosen point once more at two fresh seeds (the held-out round, polish_holdout)
    optimum_now = client.get(f"{API}/campaigns/{cid}/optimum").json()
    state = optimum_now["polish"]
    assert state["steps"] >= 1
    held = set(state["holdout_seeds"])
    polish_runs = [r for r in runs if r["kind"] == "polish"]
    assert len(polish_runs) >= 8 and (len(polish_runs) - 6) % 2 == 0
    assert {r["seed"] for r in polish_runs} == confirmation_seeds | held
    assert len(held) == 2 and not held & {r["seed"] for r in own}
    points: dict[int, list[dict]] = {}
    for r in polish_runs:  # a point's runs are consecutive in std_order, one per seed
        points.setdefault((r["std_order"] - 1) // 2, []).append(r)
    for runs_of_point in points.values():
        assert {r["seed"] for r in runs_of_point} in (confirmation_seeds, held)
        assert all(r["natural"] == runs_of_point[0]["natural"] for r in runs_of_point)
    # the report is made on the held-out batteries, one per seed, at the optimum it reports
    final = client.get(f"{API}/campaigns/{cid}/confirmation").json()
    assert {r["seed"] for r in final["runs"]} == held
    assert final["parameters"] == pytest.approx(state["theta"])
    assert optimum_now["parameters"] == pytest.approx(state["theta"])
    # the diagnosis runs a baseline at the optimum and every candidate effect at two seeds of their own:
    # as many as the report's, none of any battery before it (the signatures' noise must not be the residuals')
    diagnosis_runs = [r for r in runs if r["kind"] == "diagnosis"]
    diagnosis_seeds = {r["seed"] for r in diagnosis_runs}
    assert len(diagnosis_seeds) == 2 and not diagnosis_seeds & (confirmation_seeds | held)
    # (every candidate the thesis fidelity builds: particle shape too, its round grains elongated)
    assert len(diagnosis_runs) == 2 * (1 + sum(c.applies_to("thesis") for c in candidates().values()))
    with app.state.session_factory() as session:
        jobs = session.query(Job).filter(Job.campaign_id == cid).all()
    assert {j.id for j in jobs} == {r["job_id"] for r in runs}
    assert len(jobs) == 13 + len(diagnosis_runs) + len(polish_runs)
    assert all(j.evaluator == "analytic" and j.spec["test"] == "battery" for j in jobs)
    assert {j.seed for j in jobs} == {r["seed"] for r in runs}
    assert iteration["parameters"]["factors"][0]["name"] == "particle_density_kg_m3"

    models = client.get(f"{API}/campaigns/{cid}/models").json()["models"]
    assert set(models) == {"fill__bulk_density_kg_m3", "cct__confined_modulus_pa", "dst__friction_angle_deg"}
    density_fit = models["fill__bulk_density_kg_m3"]["fit"]
    sources = [row["source"] for row in density_fit["anova"]]
    assert {"Model", "Curvature", "Residual", "Pure Error", "Cor Total"} <= set(sources)
    assert density_fit["has_error_estimate"] is True
    # the centre replicates measure the simulator's noise: pure error > 0 since seeds differ
    assert models["fill__bulk_density_kg_m3"]["pure_error_sd"] > 0

    optimum = client.get(f"{API}/campaigns/{cid}/optimum").json()
    for factor in campaign_body(1)["factors"]:  # inside the design box (no extrapolation asked)
        assert factor["low"] <= optimum["parameters"][factor["name"]] <= factor["high"]
    confirmation = client.get(f"{API}/campaigns/{cid}/confirmation").json()
    assert confirmation["status"] == "succeeded" and confirmation["parameters"] == optimum["parameters"]
    # the final optimum's batteries are at the held-out seeds (the polish took a step)
    assert {r["seed"] for r in confirmation["runs"]} == held

    report = client.get(f"{API}/campaigns/{cid}/report").json()
    rows = {r["quantity"]: r for r in report["targets"]}
    density, modulus, phi = rows["bulk_density_kg_m3"], rows["confined_modulus_pa"], rows["friction_angle_deg"]
    assert density["measured"] == 1397.8 or math.isclose(density["measured"], 1397.8)  # Table 4.5
    assert modulus["measured"] == 8.69e6 and phi["measured"] == 60.6  # Table 4.10
    for row in (density, modulus, phi):
        assert row["status"] == "modelled"
        low, high = row["prediction_interval"]
        assert low < row["predicted"] < high
        assert row["confirmation_in_interval"] == (low <= row["confirmed"] <= high)
        # the mean of the two confirmation batteries, whose single-run scatter counts divided by 2
        assert math.isclose(row["confirmed"], sum(row["confirmed_per_seed"]) / 2)
        expected_z = (row["confirmed"] - row["measured"]) / math.hypot(row["measured_uncertainty"],
                                                                        row["simulator_sd"] / math.sqrt(2))
        assert math.isclose(row["standardised_residual"], expected_z)
    # density and modulus lie inside what the box can produce (rho_b = rho_p x solid fraction ~0.55;
    # E' grows linearly with k_p): the optimum matches them
    assert density["reachable"] and abs(density["predicted_standardised_residual"]) < 1
    assert modulus["reachable"] and abs(modulus["predicted_standardised_residual"]) < 1
    # E' was published as an average only: its uncertainty is the stated 5 % assumption, flagged
    assert modulus["uncertainty_assumed"] and math.isclose(modulus["measured_uncertainty"], 0.05 * 8.69e6)
    assert density["uncertainty_assumed"] is False
    # Round particles without rolling resistance cap the stand-in's friction angle (calibration/standin.py) at
    # the ceiling 28 deg + 0.8 x dilatancy (at most 2 + 6 deg) + box friction 2 x mu_pw (mu_pw 0.62): about
    # 36 deg, safely below 42 deg, so 60.6 deg (an angular aggregate) is > 3 standard uncertainties (3.03 deg)
    # beyond reach: the missing effect.
    assert phi["reachable"] is False and phi["reachability"] > (60.6 - 42.0) / 3.03 - 1e-9
    assert report["verdict"] == "targets out of reach"
    assert report["unreachable"] == ["dst__friction_angle_deg"]
    # the diagnosis judged the model on both tests: Holm over the omnibus lack of fit and the directed test
    adequacy = report["adequacy"]
    assert math.isclose(adequacy["p_value"], min(1.0, 2 * min(adequacy["omnibus_p"], adequacy["directed"]["p_value"])))
    assert adequacy["omnibus_p"] == report["lack_of_fit"]["p_value"]  # the same batteries at the optimum
    assert adequacy["fails"] == (adequacy["p_value"] < 0.05)
    (entry,) = client.get(f"{API}/campaigns/{cid}/history").json()["iterations"]
    assert entry["adequacy_p"] == adequacy["p_value"] and entry["directed_p"] == adequacy["directed"]["p_value"]


def test_unmatched_and_unmodelled_targets_are_reported_not_fatal(s2):
    client, app, settings = s2
    material = client.post(f"{API}/materials", json={"name": "mixed", "measurements": [
        {"test": "fill", "quantity": "bulk_density_kg_m3", "values": [1400.0, 1390.0, 1410.0]},
        {"test": "fill", "quantity": "packing_height_m", "values": [0.33]},  # fixed by the container
        {"test": "anchor", "quantity": "peak_pull_force_n", "values": [650.0],  # no anchor test in the battery
         "condition": {"packing_height_m": 0.32, "pull_speed_m_s": 0.027}},
    ]}).json()
    body = campaign_body(material["id"], targets=None, factors=[
        {"name": "particle_density_kg_m3", "low": 2300.0, "high": 2700.0},
        {"name": "friction_pp", "low": 0.3, "high": 1.0}], design={"type": "full", "centre_runs": 2})
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    rows = {r["quantity"]: r for r in client.get(f"{API}/campaigns/{cid}/report").json()["targets"]}
    assert rows["bulk_density_kg_m3"]["status"] == "modelled"
    assert rows["packing_height_m"]["status"] == "not_modelled"
    assert "do not move it" in rows["packing_height_m"]["note"]
    assert rows["peak_pull_force_n"]["status"] == "not_simulated"


def test_a_campaign_whose_targets_are_not_simulated_is_refused_at_creation(s2):
    """Issue 31: accepted, it ran its whole design and then failed with "no target could be modelled"."""
    client, app, settings = s2
    material = client.post(f"{API}/materials", json={"name": "anchors only", "measurements": [
        {"test": "anchor", "quantity": "peak_pull_force_n", "values": [650.0],
         "condition": {"packing_height_m": 0.32, "pull_speed_m_s": 0.027}}]}).json()
    body = campaign_body(material["id"], targets=None, design={"type": "full", "centre_runs": 1})
    refused = client.post(f"{API}/campaigns", json=body)
    assert refused.status_code == 422 and refused.json()["detail"][0]["loc"] == ["body", "targets"]
    assert "no target is simulated" in refused.text and "options.include_anchor=true" in refused.text
    assert client.get(f"{API}/campaigns").json()["items"] == []


def test_campaign_fails_with_reason_when_no_target_can_be_modelled(s2):
    """Simulated but moved by no factor (the container fixes the packing height): known only from the runs."""
    client, app, settings = s2
    material = client.post(f"{API}/materials", json={"name": "height only", "measurements": [
        {"test": "fill", "quantity": "packing_height_m", "values": [0.33]}]}).json()
    body = campaign_body(material["id"], targets=None, design={"type": "full", "centre_runs": 1})
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    final = run_to_end(client, app, settings, cid)
    assert final["status"] == "failed" and "no target could be modelled" in final["error"]
    assert client.post(f"{API}/campaigns/{cid}/resume").status_code == 409


def test_next_iteration_with_an_effect_keeps_the_first(s2):
    """Iteration 2 adds rolling resistance (the analytic stand-in's hidden effect); iteration 1 stays as it was."""
    client, app, settings = s2
    cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
    assert client.post(f"{API}/campaigns/{cid}/iterations", json={}).status_code == 409  # draft
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    first = client.get(f"{API}/campaigns/{cid}/report").json()
    bad = client.post(f"{API}/campaigns/{cid}/iterations", json={"fixed_parameters": {"friction_pp": 0.5}})
    assert bad.status_code == 422  # friction_pp is a factor: cannot also be fixed
    effects = {"rolling_epsd2": {"rolling_friction": 0.3}}
    response = client.post(f"{API}/campaigns/{cid}/iterations", json={"fixed_parameters": {"effects": effects}})
    assert response.status_code == 201 and response.json()["status"] == "running"
    assert client.post(f"{API}/campaigns/{cid}/iterations", json={}).status_code == 409  # running
    assert run_to_end(client, app, settings, cid)["status"] == "completed"

    iterations = client.get(f"{API}/campaigns/{cid}/iterations").json()["items"]
    assert [it["number"] for it in iterations] == [1, 2]
    assert iterations[0]["parameters"]["effects"] == {} and iterations[1]["parameters"]["effects"] == effects
    assert client.get(f"{API}/campaigns/{cid}/report", params={"number": 1}).json()["targets"] == first["targets"]
    second = {r["quantity"]: r for r in client.get(f"{API}/campaigns/{cid}/report").json()["targets"]}
    # with rolling friction 0.3 the stand-in's ceiling rises by 30 x 0.3/0.5 = 18 deg and the dilatancy by
    # 5 x 0.3/0.5 = 3 deg (x 0.8 in phi): about 55 deg at mu_pp = 1, so 60.6 deg is now within 3 u (9.1 deg)
    assert second["friction_angle_deg"]["reachable"] is True
    second_runs = [r for r in iterations[1]["runs"] if r["kind"] in ("design", "confirmation")]
    assert len(second_runs) == 11 + 2  # the design and a confirmation battery per seed
    with app.state.session_factory() as session:
        jobs = {j.id: j for j in session.query(Job).filter(Job.campaign_id == cid).all()}
    assert all(jobs[r["job_id"]].spec["parameters"]["effects"] == effects for r in second_runs)


def test_one_confirmation_seed_gets_a_baseline_seed_of_its_own_for_the_diagnosis(s2):
    """confirmation_seeds 1: one battery at the optimum, scatter at full weight in the report; the diagnosis
    queues a baseline battery at the optimum first, at a seed the confirmation did not use, and each
    candidate at that seed (attribute.signature_seeds)."""
    client, app, settings = s2
    body = campaign_body(thesis_material_id(client), confirmation_seeds=1, polish_steps=0)
    cid = client.post(f"{API}/campaigns", json=body).json()["id"]
    client.post(f"{API}/campaigns/{cid}/start")
    assert run_to_end(client, app, settings, cid)["status"] == "completed"
    (iteration,) = client.get(f"{API}/campaigns/{cid}/iterations").json()["items"]
    (seed,) = [r["seed"] for r in iteration["runs"] if r["kind"] == "confirmation"]
    diagnosis_runs = sorted((r for r in iteration["runs"] if r["kind"] == "diagnosis"), key=lambda r: r["std_order"])
    optimum = client.get(f"{API}/campaigns/{cid}/optimum").json()["parameters"]
    (own,) = signature_seeds([seed])
    assert own != seed and diagnosis_runs[0]["natural"] == optimum
    assert {r["seed"] for r in diagnosis_runs} == {own}
    assert len(diagnosis_runs) == 1 + sum(c.applies_to("thesis") for c in candidates().values())
    report = client.get(f"{API}/campaigns/{cid}/report").json()
    assert report["confirmation_seeds"] == [seed]
    for row in report["targets"]:
        if row["status"] == "modelled":
            expected_z = (row["confirmed"] - row["measured"]) / math.hypot(row["measured_uncertainty"],
                                                                            row["simulator_sd"])
            assert math.isclose(row["standardised_residual"], expected_z)
