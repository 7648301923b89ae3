"""The campaign state machine lives in the database: a restarted service carries on where it was."""
from __future__ import annotations

import pytest
from sqlalchemy import select

from engine.candidates import candidates

from conftest_s2 import API, campaign_body, drain, run_to_end, running_app, s2_settings, thesis_material_id
from service.campaigns.runner import CampaignRunner
from service.models.campaign import CampaignRun
from service.models.job import Job
from service import queue

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)


def test_restart_mid_campaign_completes_without_duplicate_jobs(db_url):
    settings = s2_settings(db_url)
    with running_app(settings) as (client, app):
        # every phase at its fullest (polishing always, the diagnosis at every seed), so each is restarted through
        body = campaign_body(thesis_material_id(client), polish_when="always", polish_jacobian="batteries",
                             adaptive_replicates=False)
        cid = client.post(f"{API}/campaigns", json=body).json()["id"]
        client.post(f"{API}/campaigns/{cid}/start")
        CampaignRunner(app.state.session_factory, settings).tick()
        assert drain(app, settings, max_jobs=5) == 5  # service "dies" with 6 batteries still queued
        before = client.get(f"{API}/campaigns/{cid}").json()
        assert before["status"] == "running" and before["phase"] == "batteries"

    with running_app(settings) as (client, app):  # a new process: new app, new runner, same database file
        status = client.get(f"{API}/campaigns/{cid}").json()
        assert status["phase"] == "batteries" and status["runs_total"] == 11
        final = run_to_end(client, app, settings, cid)
        assert final["status"] == "completed", final["error"]
        with app.state.session_factory() as session:
            jobs = session.scalars(select(Job).where(Job.campaign_id == cid)).all()
            runs = session.scalars(select(CampaignRun)).all()
        # 11 batteries + confirmation and polishing at two seeds + a baseline and each candidate effect at
        # two seeds of their own: one job per run, none twice
        kinds = [r.kind for r in runs]
        assert kinds.count("design") == 11 and kinds.count("confirmation") == 2 and kinds.count("polish") >= 6
        assert kinds.count("diagnosis") == 2 * (1 + sum(c.applies_to("thesis") for c in candidates().values()))
        assert sorted(j.id for j in jobs) == sorted(r.job_id for r in runs)
        report = client.get(f"{API}/campaigns/{cid}/report").json()
        assert len(report["targets"]) == 3


def test_restart_mid_diagnosis_resumes_without_duplicate_jobs(db_url):
    """The service dies with the diagnosis batteries half run: the new one queues none twice and
    ranks the effects from the batteries the old one ran."""
    settings = s2_settings(db_url)
    n_diagnosis = 2 * (1 + sum(c.applies_to("thesis") for c in candidates().values()))  # baseline + each
    with running_app(settings) as (client, app):
        cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
        client.post(f"{API}/campaigns/{cid}/start")
        runner = CampaignRunner(app.state.session_factory, settings)
        for _ in range(20):
            runner.tick()
            if client.get(f"{API}/campaigns/{cid}").json()["phase"] == "diagnosis":
                break
            drain(app, settings)
        runner.tick()  # queues the diagnosis batteries
        assert drain(app, settings, max_jobs=3) == 3
        before = client.get(f"{API}/campaigns/{cid}").json()
        assert before["phase"] == "diagnosis"

    with running_app(settings) as (client, app):
        final = run_to_end(client, app, settings, cid)
        assert final["status"] == "completed", final["error"]
        with app.state.session_factory() as session:
            jobs = session.scalars(select(Job).where(Job.campaign_id == cid)).all()
            runs = session.scalars(select(CampaignRun)).all()
        assert sum(r.kind == "diagnosis" for r in runs) == n_diagnosis
        assert sorted(j.id for j in jobs) == sorted(r.job_id for r in runs)  # one job per run, none twice
        diagnosis = client.get(f"{API}/campaigns/{cid}/diagnosis").json()
        assert diagnosis["batteries"] == n_diagnosis and diagnosis["ranking"]


def test_restart_between_queuing_and_recording_a_job_finds_the_same_job(db_url):
    """A crash after submit_job committed but before the run stored the job id must not queue a twin."""
    settings = s2_settings(db_url)
    with running_app(settings) as (client, app):
        cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
        client.post(f"{API}/campaigns/{cid}/start")
        sf = app.state.session_factory
        CampaignRunner(sf, settings).tick()
        with sf() as session:
            run = session.scalars(select(CampaignRun).order_by(CampaignRun.id)).first()
            lost_job_id = run.job_id
            run.job_id, run.status = None, "pending"  # as if the process died before this write
            session.commit()
        CampaignRunner(sf, settings).tick()
        with sf() as session:
            assert session.get(CampaignRun, run.id).job_id == lost_job_id
            assert session.query(Job).filter(Job.campaign_id == cid).count() == 11


def test_a_failed_battery_fails_the_campaign_with_its_reason(db_url):
    settings = s2_settings(db_url)
    with running_app(settings) as (client, app):
        cid = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client))).json()["id"]
        client.post(f"{API}/campaigns/{cid}/start")
        sf = app.state.session_factory
        CampaignRunner(sf, settings).tick()
        with sf() as session:
            job_id = session.scalars(select(Job.id).where(Job.campaign_id == cid)).first()
            queue.cancel_job(session, job_id)
        final = run_to_end(client, app, settings, cid)
        assert final["status"] == "failed"
        assert f"(job {job_id}) cancelled" in final["error"]
