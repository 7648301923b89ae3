"""Helpers shared by S2's tests (materials, designs, campaigns, schedules, web); imported explicitly.

Each test gets its own database (``db_url``: a SQLite file, or PostgreSQL in modules marked
``postgres``); the app runs without executors or background ticks so that tests drive the campaign
runner, the scheduler and the workers themselves, step by step and deterministically.
"""
from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from service_net import LOCAL_BASE_URL

from service.app import create_app
from service.campaigns.runner import CampaignRunner
from service.config import Settings
from service.workers.local import Worker

API = "/api/v1"
THESIS_MATERIAL = "thesis-coarse-aggregate"


def s2_settings(database: Path | str) -> Settings:
    """``database``: a URL (the ``db_url`` fixture: SQLite or PostgreSQL), or a directory for a SQLite file."""
    url = database if isinstance(database, str) else f"sqlite:///{(database / 's2.db').as_posix()}"
    return Settings(database_url=url, start_workers=False, start_background=False, seed_materials=True,
                    lease_s=30.0, heartbeat_s=5.0)


@contextmanager
def running_app(settings: Settings):
    """The real app with its lifespan (migrations, bundled material seed); yields (client, app)."""
    app = create_app(settings)
    with TestClient(app, base_url=LOCAL_BASE_URL) as client:
        yield client, app


@pytest.fixture
def s2(db_url):
    settings = s2_settings(db_url)
    with running_app(settings) as (client, app):
        yield client, app, settings


def thesis_material_id(client) -> int:
    return next(m["id"] for m in client.get(f"{API}/materials").json()["items"] if m["name"] == THESIS_MATERIAL)


def editable_thesis_copy(client, name: str = "thesis copy") -> int:
    """The bundled material is read-only; tests that add or delete measurements edit a copy of it."""
    response = client.post(f"{API}/materials/{thesis_material_id(client)}/copy", json={"name": name})
    assert response.status_code == 201, response.text
    return response.json()["id"]


def drain(app, settings: Settings, max_jobs: int | None = None) -> int:
    """Run queued jobs in this process through S1's worker code; returns how many ran."""
    worker = Worker(app.state.session_factory, settings, worker_id="s2-test-worker")
    done = 0
    while max_jobs is None or done < max_jobs:
        if worker.run_one() is None:
            break
        done += 1
    return done


def campaign_body(material_id: int, **overrides) -> dict:
    """Three factors that move the three calibrated targets of the thesis (Sec. 4.5.4)."""
    body = {
        "name": "thesis calibration", "material_id": material_id, "evaluator": "analytic", "fidelity": "thesis",
        "factors": [
            {"name": "particle_density_kg_m3", "low": 2300.0, "high": 2700.0, "unit": "kg/m3"},
            {"name": "particle_stiffness_n_per_m", "low": 1.0e6, "high": 3.0e6, "unit": "N/m"},
            {"name": "friction_pp", "low": 0.3, "high": 1.0},
        ],
        "design": {"type": "full", "centre_runs": 3},
        "targets": [
            {"test": "fill", "quantity": "bulk_density_kg_m3"},
            {"test": "cct", "quantity": "confined_modulus_pa"},
            {"test": "dst", "quantity": "friction_angle_deg"},
        ],
        "seed": 11,
    }
    body.update(overrides)
    return body


def run_to_end(client, app, settings, campaign_id: int, max_rounds: int = 20) -> dict:
    runner = CampaignRunner(app.state.session_factory, settings)
    for _ in range(max_rounds):
        runner.tick()
        drain(app, settings)
        status = client.get(f"{API}/campaigns/{campaign_id}").json()
        if status["status"] in ("completed", "failed"):
            return status
    raise AssertionError(f"campaign {campaign_id} did not finish: {status}")


def error_loc(response) -> list:
    return response.json()["detail"][0]["loc"]
