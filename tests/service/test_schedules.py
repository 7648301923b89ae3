"""Cron parsing, the scheduler's missed-run policy, new-measurement gating, restart safety, and the API."""
from __future__ import annotations

from datetime import datetime, timedelta, timezone

import pytest
from conftest_s2 import (API, campaign_body, editable_thesis_copy, error_loc, running_app, s2,  # noqa: F401
                         run_to_end, s2_settings, thesis_material_id)
from service.models.campaign import Campaign
from service.models.schedule import Schedule
from service.schedules.cron import CronError, parse_cron
from service.schedules.scheduler import Scheduler

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)

T0 = datetime(2026, 11, 20, 12, 0)  # a Friday


# -- cron ---------------------------------------------------------------------------------------

@pytest.mark.parametrize("expr, after, expected", [
    ("0 2 * * *", T0, [datetime(2026, 11, 21, 2, 0), datetime(2026, 11, 22, 2, 0)]),
    ("*/20 * * * *", T0, [datetime(2026, 11, 20, 12, 20), datetime(2026, 11, 20, 12, 40)]),
    ("5/20 12 * * *", T0, [datetime(2026, 11, 20, 12, 5), datetime(2026, 11, 20, 12, 25)]),
    ("30 9-17/4 * * mon-fri", T0, [datetime(2026, 11, 20, 13, 30), datetime(2026, 11, 20, 17, 30),
                                  datetime(2026, 11, 23, 9, 30)]),
    ("0 0 1,15 * *", T0, [datetime(2026, 12, 1), datetime(2026, 12, 15)]),
    ("0 0 * feb sun", T0, [datetime(2027, 2, 7), datetime(2027, 2, 14)]),
    ("0 0 * * 7", T0, [datetime(2026, 11, 22), datetime(2026, 11, 29)]),  # 7 is Sunday too
    # day-of-month and day-of-week both restricted: either matches (Vixie cron)
    ("0 0 13 * fri", T0, [datetime(2026, 11, 27), datetime(2026, 12, 4), datetime(2026, 12, 11),
                          datetime(2026, 12, 13)]),
    ("0 0 29 2 *", T0, [datetime(2028, 2, 29)]),  # next leap day
    ("@daily", T0, [datetime(2026, 11, 21), datetime(2026, 11, 22)]),
    ("@hourly", T0, [datetime(2026, 11, 20, 13), datetime(2026, 11, 20, 14)]),
    ("@weekly", T0, [datetime(2026, 11, 22)]),
    ("@monthly", T0, [datetime(2026, 12, 1)]),
    ("@yearly", T0, [datetime(2027, 1, 1)]),
    ("59 23 31 12 *", datetime(2026, 12, 31, 23, 59), [datetime(2027, 12, 31, 23, 59)]),  # strictly after
])
def test_cron_next_times(expr, after, expected):
    assert parse_cron(expr).upcoming(after, len(expected)) == expected


def test_cron_ignores_seconds_and_returns_strictly_later_minutes():
    assert parse_cron("* * * * *").next_after(datetime(2026, 1, 1, 0, 0, 30)) == datetime(2026, 1, 1, 0, 1)


@pytest.mark.parametrize("expr", ["", "* * * *", "* * * * * *", "60 * * * *", "* 24 * * *", "* * 0 * *",
                                  "* * * 13 *", "* * * * 8", "*/0 * * * *", "5-1 * * * *", "a * * * *",
                                  "1,,2 * * * *", "0 0 31 2 *", "@fortnightly", "* * * foo *"])
def test_cron_rejects_bad_expressions(expr):
    with pytest.raises(CronError):
        parse_cron(expr)


# -- scheduler ------------------------------------------------------------------------------------

def _schedule(client, material_id, cron="0 2 * * *", **extra) -> dict:
    body = {"name": "nightly", "cron": cron, "template": campaign_body(material_id), **extra}
    response = client.post(f"{API}/schedules", json=body)
    assert response.status_code == 201, response.text
    return response.json()


def _set_next(app, schedule_id, when):
    with app.state.session_factory() as session:
        session.get(Schedule, schedule_id).next_run_at = when
        session.commit()


def test_due_schedule_starts_a_campaign_once(s2):
    client, app, settings = s2
    schedule = _schedule(client, thesis_material_id(client))
    _set_next(app, schedule["id"], datetime(2026, 11, 21, 2, 0))
    scheduler = Scheduler(app.state.session_factory, settings)
    assert scheduler.tick(datetime(2026, 11, 21, 1, 59)) == []
    started = scheduler.tick(datetime(2026, 11, 21, 2, 0, 1, tzinfo=timezone.utc))
    assert len(started) == 1
    campaign = client.get(f"{API}/campaigns/{started[0]}").json()
    assert campaign["status"] == "running" and campaign["schedule_id"] == schedule["id"]
    assert campaign["name"] == "thesis calibration @ 2026-11-21 02:00Z"
    assert scheduler.tick(datetime(2026, 11, 21, 2, 0, 30)) == []  # same due time never fires twice
    shown = client.get(f"{API}/schedules/{schedule['id']}").json()
    assert shown["next_run_at"] == "2026-11-22T02:00:00Z" and shown["last_campaign_id"] == started[0]
    assert shown["recent_firings"][0]["missed_count"] == 0


def test_missed_runs_coalesce_into_one_catch_up(db_url):
    """Service down three nights: on restart one campaign starts, covering the two missed due times."""
    settings = s2_settings(db_url)
    with running_app(settings) as (client, app):
        schedule = _schedule(client, thesis_material_id(client))
        _set_next(app, schedule["id"], datetime(2026, 11, 18, 2, 0))
    with running_app(settings) as (client, app):  # restarted at 09:00 on the 20th
        started = Scheduler(app.state.session_factory, settings).tick(datetime(2026, 11, 20, 9, 0))
        assert len(started) == 1
        (firing,) = client.get(f"{API}/schedules/{schedule['id']}/firings").json()["items"]
        assert firing["due_at"] == "2026-11-20T02:00:00Z" and firing["missed_count"] == 2
        assert client.get(f"{API}/schedules/{schedule['id']}").json()["next_run_at"] == "2026-11-21T02:00:00Z"
        assert Scheduler(app.state.session_factory, settings).tick(datetime(2026, 11, 20, 9, 1)) == []
        with app.state.session_factory() as session:
            assert session.query(Campaign).count() == 1


def test_skip_policy_drops_stale_due_times(s2):
    client, app, settings = s2
    schedule = _schedule(client, thesis_material_id(client), missed_run_policy="skip")
    _set_next(app, schedule["id"], datetime(2026, 11, 20, 2, 0))
    assert Scheduler(app.state.session_factory, settings).tick(datetime(2026, 11, 20, 9, 0)) == []
    (firing,) = client.get(f"{API}/schedules/{schedule['id']}/firings").json()["items"]
    assert firing["campaign_id"] is None and "policy skip" in firing["skipped_reason"]
    # within the grace period it still fires
    _set_next(app, schedule["id"], datetime(2026, 11, 21, 2, 0))
    assert len(Scheduler(app.state.session_factory, settings).tick(datetime(2026, 11, 21, 2, 1))) == 1


def test_only_when_new_measurements_arrived(s2):
    client, app, settings = s2
    material_id = editable_thesis_copy(client)
    schedule = _schedule(client, material_id, only_if_new_measurements=True)
    scheduler = Scheduler(app.state.session_factory, settings)
    day = datetime(2026, 11, 21, 2, 0)
    _set_next(app, schedule["id"], day)
    assert len(scheduler.tick(day)) == 1  # first run: everything is new
    _set_next(app, schedule["id"], day + timedelta(days=1))
    assert scheduler.tick(day + timedelta(days=1)) == []
    firings = client.get(f"{API}/schedules/{schedule['id']}/firings").json()["items"]
    assert firings[-1]["skipped_reason"] == "no new measurements since the last run"
    added = client.post(f"{API}/materials/{material_id}/measurements", json={
        "test": "dst", "quantity": "residual_shear_stress_pa", "values": [17.0, 18.0], "unit": "kPa",
        "condition": {"normal_stress_pa": 24000.0}})
    assert added.status_code == 201, added.text
    _set_next(app, schedule["id"], day + timedelta(days=2))
    assert len(scheduler.tick(day + timedelta(days=2))) == 1


def test_disabled_schedules_do_not_fire_and_reenabling_skips_the_gap(s2):
    client, app, settings = s2
    schedule = _schedule(client, thesis_material_id(client), cron="@hourly")
    assert client.patch(f"{API}/schedules/{schedule['id']}", json={"enabled": False}).json()["enabled"] is False
    _set_next(app, schedule["id"], datetime(2026, 11, 20, 2, 0))
    assert Scheduler(app.state.session_factory, settings).tick(datetime(2026, 11, 20, 9, 0)) == []
    enabled = client.patch(f"{API}/schedules/{schedule['id']}", json={"enabled": True}).json()
    assert enabled["next_run_at"] > datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M")
    changed = client.patch(f"{API}/schedules/{schedule['id']}", json={"cron": "15 3 * * *"}).json()
    assert changed["cron"] == "15 3 * * *" and changed["next_run_at"].endswith("T03:15:00Z")


def test_deleted_material_skips_with_reason(s2):
    client, app, settings = s2
    material = client.post(f"{API}/materials", json={"name": "temp"}).json()
    schedule = _schedule(client, material["id"])
    client.delete(f"{API}/materials/{material['id']}")
    _set_next(app, schedule["id"], datetime(2026, 11, 21, 2, 0))
    assert Scheduler(app.state.session_factory, settings).tick(datetime(2026, 11, 21, 2, 0)) == []
    (firing,) = client.get(f"{API}/schedules/{schedule['id']}/firings").json()["items"]
    assert "no longer exists" in firing["skipped_reason"]


def test_two_schedulers_on_one_database_fire_once(s2, monkeypatch):
    """B fires while A is between reading the schedule and claiming it: A's conditional claim loses."""
    from service.schedules import scheduler as scheduler_module

    client, app, settings = s2
    schedule = _schedule(client, thesis_material_id(client))
    due = datetime(2026, 11, 21, 2, 0)
    _set_next(app, schedule["id"], due)
    a, b = Scheduler(app.state.session_factory, settings), Scheduler(app.state.session_factory, settings)
    real_parse, b_started = scheduler_module.parse_cron, []

    def parse_while_b_fires(expression):
        if not b_started:
            b_started.append(None)  # B's own parse must not recurse
            b_started[0] = b.tick(due)
        return real_parse(expression)

    monkeypatch.setattr(scheduler_module, "parse_cron", parse_while_b_fires)
    assert a.tick(due) == []
    assert len(b_started[0]) == 1
    with app.state.session_factory() as session:
        assert session.query(Campaign).count() == 1


# -- API -------------------------------------------------------------------------------------------

def test_schedule_api_crud_and_errors(s2):
    client, _, _ = s2
    material_id = thesis_material_id(client)
    created = _schedule(client, material_id)
    assert created["missed_run_policy"] == "coalesce" and created["material_id"] == material_id
    assert [s["id"] for s in client.get(f"{API}/schedules").json()["items"]] == [created["id"]]
    bad_cron = client.post(f"{API}/schedules", json={"name": "x", "cron": "61 * * * *",
                                                      "template": campaign_body(material_id)})
    assert bad_cron.status_code == 422 and error_loc(bad_cron) == ["body", "cron"]
    bad_template = client.post(f"{API}/schedules", json={"name": "x", "cron": "@daily",
                                                          "template": campaign_body(material_id, evaluator="x")})
    assert bad_template.status_code == 422 and error_loc(bad_template) == ["body", "template", "evaluator"]
    missing_material = client.post(f"{API}/schedules", json={"name": "x", "cron": "@daily",
                                                              "template": campaign_body(999)})
    assert missing_material.status_code == 404 and error_loc(missing_material) == ["body", "template", "material_id"]
    policy = client.post(f"{API}/schedules", json={"name": "x", "cron": "@daily", "missed_run_policy": "all",
                                                    "template": campaign_body(material_id)})
    assert policy.status_code == 422 and error_loc(policy) == ["body", "missed_run_policy"]
    patch_bad = client.patch(f"{API}/schedules/{created['id']}", json={"cron": "* * *"})
    assert patch_bad.status_code == 422 and error_loc(patch_bad) == ["body", "cron"]
    for method, path in [("get", ""), ("get", "/firings"), ("delete", "")]:
        response = getattr(client, method)(f"{API}/schedules/777{path}")
        assert response.status_code == 404 and error_loc(response) == ["path", "schedule_id"]
    assert client.patch(f"{API}/schedules/777", json={"enabled": False}).status_code == 404
    preview = client.get(f"{API}/schedules/cron-preview", params={"expr": "@daily", "count": 2}).json()
    assert len(preview["next"]) == 2 and all(t.endswith("T00:00:00Z") for t in preview["next"])
    bad_preview = client.get(f"{API}/schedules/cron-preview", params={"expr": "0 25 * * *"})
    assert bad_preview.status_code == 422 and error_loc(bad_preview) == ["query", "expr"]
    assert client.delete(f"{API}/schedules/{created['id']}").status_code == 204
    assert client.get(f"{API}/schedules").json()["items"] == []


def test_a_scheduled_campaign_can_run_the_loop_unattended(s2):
    """Automatic mode in a schedule's template: the nightly campaign diagnoses, adds the indicated
    effect and stops with a reason, with nobody at the keyboard."""
    client, app, settings = s2
    body = {"name": "nightly", "cron": "0 2 * * *",
            "template": campaign_body(thesis_material_id(client), targets=None, automatic=True, max_iterations=2)}
    response = client.post(f"{API}/schedules", json=body)
    assert response.status_code == 201, response.text
    _set_next(app, response.json()["id"], datetime(2026, 11, 21, 2, 0))
    (cid,) = Scheduler(app.state.session_factory, settings).tick(datetime(2026, 11, 21, 2, 0, 1))
    final = run_to_end(client, app, settings, cid, max_rounds=60)
    assert final["status"] == "completed" and final["stop_reason"], final
    history = client.get(f"{API}/campaigns/{cid}/history").json()["iterations"]
    assert len(history) == 2 and history[0]["effect_added_next"]
