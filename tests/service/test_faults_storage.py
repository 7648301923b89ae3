"""Issue 13, faults: clean job errors, read-only reference data, one-line storage errors, worker back-off,
and the contract details (time zones, the curves index, documented status codes)."""
from __future__ import annotations

import logging
import subprocess
import threading
import time

import pytest
from conftest_s2 import API, THESIS_MATERIAL, s2, thesis_material_id  # noqa: F401

from service.config import Settings
from service.materials import seed_bundled_materials
from service.migrate import upgrade
from service.models.material import Material, Measurement
from service.workers.local import Worker

pytestmark = pytest.mark.postgres  # each database test runs on SQLite and on PostgreSQL (backends.py)


def locs(response) -> list[list]:
    return [err["loc"] for err in response.json()["detail"]]


# -- failed jobs --------------------------------------------------------------------------------------

def test_failed_job_shows_one_line_and_logs_the_traceback(client, caplog):
    job = client.post(f"{API}/jobs", json={"evaluator": "analytic"}).json()

    def broken(_evaluator, _spec, _progress, _should_cancel):
        raise FileNotFoundError(2, "No such file or directory", "/srv/demcal/engine/lab/tables/missing.json")

    app = client.app
    worker = Worker(app.state.session_factory, app.state.settings, "fault-test", evaluate=broken)
    with caplog.at_level(logging.WARNING, logger="service.workers.local"):
        assert worker.run_one() == "failed"
    error = client.get(f"{API}/jobs/{job['id']}").json()["error"]
    assert error.startswith("FileNotFoundError:") and "missing.json" in error
    assert "Traceback" not in error and "/srv/" not in error and "\n" not in error
    logged = "\n".join(r.getMessage() for r in caplog.records)
    assert "Traceback" in logged and "/srv/demcal/engine/lab/tables/missing.json" in logged


def test_stored_traceback_of_an_older_job_is_not_shown(client):
    from service.models.job import Job

    job = client.post(f"{API}/jobs", json={"evaluator": "analytic"}).json()
    with client.app.state.session_factory() as session:
        row = session.get(Job, job["id"])
        row.status, row.error = "failed", ('ValueError: bad effect\n\nTraceback (most recent call last):\n'
                                           '  File "/home/ops/demcal/service/workers/local.py", line 88')
        session.commit()
    assert client.get(f"{API}/jobs/{job['id']}").json()["error"] == "ValueError: bad effect"


# -- read-only bundled material -------------------------------------------------------------------------

def test_bundled_material_is_read_only_and_copyable(s2):
    client, _, _ = s2
    material_id = thesis_material_id(client)
    before = client.get(f"{API}/materials/{material_id}").json()
    first = before["measurements"][0]["id"]
    for response in (client.delete(f"{API}/materials/{material_id}"),
                     client.delete(f"{API}/materials/{material_id}/measurements/{first}"),
                     client.post(f"{API}/materials/{material_id}/measurements",
                                 json={"test": "dst", "quantity": "cohesion_pa", "values": [8500.0]})):
        assert response.status_code == 409 and locs(response) == [["path", "material_id"]]
        assert "copy" in response.json()["detail"][0]["msg"]
    assert client.get(f"{API}/materials/{material_id}").json() == before
    copy = client.post(f"{API}/materials/{material_id}/copy", json={"name": "mine"})
    assert copy.status_code == 201 and not copy.json()["bundled"]
    strip = lambda ms: [{k: v for k, v in m.items() if k not in ("id", "material_id", "created_at")} for m in ms]  # noqa: E731
    assert strip(copy.json()["measurements"]) == strip(before["measurements"])
    assert client.delete(f"{API}/materials/{copy.json()['id']}/measurements/"
                         f"{copy.json()['measurements'][0]['id']}").status_code == 204
    again = client.post(f"{API}/materials/{material_id}/copy", json={"name": "mine"})
    assert again.status_code == 409 and locs(again) == [["body", "name"]]


def test_missing_reference_measurements_are_restored_at_start(s2):
    """Deleted before the material was read-only (or by hand in the database): back at the next start."""
    client, app, _ = s2
    material_id = thesis_material_id(client)
    complete = client.get(f"{API}/materials/{material_id}").json()["measurements"]
    with app.state.session_factory() as session:
        for row in session.query(Measurement).filter_by(material_id=material_id).limit(3):
            session.delete(row)
        session.commit()
    assert len(client.get(f"{API}/materials/{material_id}").json()["measurements"]) == len(complete) - 3
    with app.state.session_factory() as session:
        seed_bundled_materials(session)
        seed_bundled_materials(session)  # idempotent
        assert session.query(Material).filter_by(name=THESIS_MATERIAL).count() == 1
    restored = client.get(f"{API}/materials/{material_id}").json()["measurements"]
    key = lambda m: (m["test"], m["quantity"], sorted(m["condition"].items()), m["values"])  # noqa: E731
    assert sorted(map(key, restored)) == sorted(map(key, complete))


# -- storage failures -----------------------------------------------------------------------------------

def _readonly_url(tmp_path) -> str:
    """A database SQLite opens read-only (file permissions do not stop root, which CI may be)."""
    path = tmp_path / "ro.db"
    upgrade(f"sqlite:///{path.as_posix()}")
    return f"sqlite:///file:{path.as_posix()}?mode=ro&uri=true"


@pytest.mark.parametrize("command", ["serve", "worker"])
def test_unwritable_database_is_one_line_and_exit_1(tmp_path, demcal_cmd, service_env, command):
    url = _readonly_url(tmp_path)
    args = ["serve", "--port", "0", "--workers", "0"] if command == "serve" else ["worker"]
    proc = subprocess.run(demcal_cmd(*args, "--db", url), env=service_env(url), capture_output=True, text=True,
                          timeout=120)
    assert proc.returncode == 1
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "readonly" in lines[0] and "ro.db" in lines[0], proc.stderr


def test_uncreatable_directory_is_one_line_and_exit_1(tmp_path, demcal_cmd, service_env):
    blocker = tmp_path / "a-file"
    blocker.write_text("not a directory")
    url = f"sqlite:///{(blocker / 'data' / 'demcal.db').as_posix()}"
    proc = subprocess.run(demcal_cmd("serve", "--port", "0", "--workers", "0", "--db", url), env=service_env(url),
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and "a-file" in lines[0], proc.stderr


def test_worker_on_unwritable_database_backs_off_and_says_why(tmp_path, caplog):
    from service.db import make_engine, make_session_factory

    writable = f"sqlite:///{(tmp_path / 'ro.db').as_posix()}"
    url = _readonly_url(tmp_path)
    settings = Settings(database_url=writable, poll_interval_s=0.05)
    rw = make_engine(writable)
    from engine.lab.spec import JobSpec
    from service import queue

    with make_session_factory(rw, settings)() as session:
        queue.submit_job(session, JobSpec(), evaluator="analytic")
    rw.dispose()
    engine = make_engine(url)
    worker = Worker(make_session_factory(engine, settings), settings, "ro-worker")
    thread = threading.Thread(target=worker.run, daemon=True)
    with caplog.at_level(logging.INFO, logger="service.workers.local"):
        thread.start()
        time.sleep(3.0)
        worker.stop.set()
        thread.join(10)
    engine.dispose()
    errors = [r for r in caplog.records if r.levelno >= logging.ERROR]
    # polling every 0.05 s would have tried ~60 times in 3 s; backing off doubles each wait (0.1, 0.2, ...)
    assert len(errors) == 1 and errors[0].exc_info is None
    assert "readonly" in errors[0].getMessage() and "retrying in" in errors[0].getMessage()


# -- contract --------------------------------------------------------------------------------------------

def test_job_timestamps_carry_their_zone(client):
    job = client.post(f"{API}/jobs", json={"evaluator": "analytic"}).json()
    assert job["created_at"].endswith("Z")
    listed = client.get(f"{API}/jobs").json()["items"][0]
    assert listed["created_at"] == job["created_at"] and listed["started_at"] is None


def test_openapi_documents_error_codes_and_bounds(client):
    schema = client.get(f"{API}/openapi.json").json()
    paths = schema["paths"]
    submit = paths["/api/v1/jobs"]["post"]["responses"]
    assert {"200", "201", "400", "401", "409", "422", "429"} <= set(submit)
    assert {"401", "404", "409", "422"} <= set(paths["/api/v1/jobs/{job_id}/cancel"]["post"]["responses"])
    assert {"404", "422"} <= set(paths["/api/v1/materials/{material_id}"]["get"]["responses"])
    job_id = next(p for p in paths["/api/v1/jobs/{job_id}"]["get"]["parameters"] if p["name"] == "job_id")
    assert job_id["schema"]["maximum"] == 2**31 - 1  # ids are INTEGER columns, 32-bit on PostgreSQL
    micro = schema["components"]["schemas"]["MicroParameters"]["properties"]
    assert micro["particle_density_kg_m3"]["maximum"] == 22_590.0  # osmium


def test_405_lists_every_documented_method(client):
    """Starlette's 405 named only the first route's methods (``Allow: POST`` for /campaigns)."""
    for method, path, allowed in [("OPTIONS", "/campaigns", "GET, POST"), ("PUT", "/materials/1", "DELETE, GET"),
                                  ("PATCH", "/jobs", "GET, POST")]:
        r = client.request(method, f"{API}{path}")
        assert r.status_code == 405 and r.headers["allow"] == allowed


def test_quantities_publish_their_physical_bounds(client):
    quantities = client.get(f"{API}/materials/quantities").json()
    porosity = quantities["fill"]["porosity"]["bounds"]
    assert (porosity["low"], porosity["high"]) == (0.0, 1.0)  # a volume fraction, both ends open
    assert not porosity["low_inclusive"] and not porosity["high_inclusive"]
    assert quantities["dst"]["friction_angle_deg"]["bounds"]["high"] == 90.0
    assert quantities["anchor"]["peak_pull_force_n"]["bounds"]["high"] is None  # no ceiling but finiteness
