"""A job's wall time before it runs: the cost model's particles x simulated seconds, scaled by the ratio this
service's finished jobs measured (service.wall_estimate). The figures follow from that definition: a job
of the same set-up as finished ones of 10 and 30 s gets their median, 20 s; one of another set-up gets the
finished jobs' seconds per particle-simulated-second times its own particles x simulated seconds."""
from __future__ import annotations

import pytest
from conftest_s2 import campaign_body, s2, thesis_material_id  # noqa: F401

from engine.lab.cost import estimate_view
from engine.lab.spec import JobSpec
from service.models.job import Job
from service.vocabulary import JobStatus

pytestmark = pytest.mark.postgres

API = "/api/v1"


def _submit(client, **body):
    body.setdefault("evaluator", "analytic")
    r = client.post(f"{API}/jobs", json=body)
    assert r.status_code == 201, r.text
    return r.json()


def _finish(client, job_id: int, wall_s: float) -> None:
    """Mark a job finished with a wall time, as a worker's completion does (the result is not read here)."""
    with client.app.state.session_factory() as session:
        job = session.get(Job, job_id)
        job.status, job.wall_time_s = JobStatus.SUCCEEDED, wall_s
        session.commit()


def _size(spec: dict) -> float:
    view = estimate_view(JobSpec.model_validate(spec))
    return view["particles"] * view["simulated_time_s"]


def test_no_record_no_guess(client):
    estimate = _submit(client, test="fill", seed=1)["estimate"]
    assert estimate["wall_time_s"] is None and estimate["wall_time_range_s"] is None
    assert estimate["wall_time_basis"] == "no finished analytic job on this service yet"


def test_the_same_set_up_gives_the_median_of_its_finished_jobs(client):
    for seed, wall_s in ((1, 10.0), (2, 30.0), (3, 20.0)):
        _finish(client, _submit(client, test="fill", seed=seed)["id"], wall_s)
    estimate = _submit(client, test="fill", seed=4)["estimate"]
    assert estimate["wall_time_s"] == pytest.approx(20.0)
    assert estimate["wall_time_range_s"] == pytest.approx([10.0, 30.0])
    assert estimate["wall_time_basis"] == "3 finished analytic jobs of the same set-up on this service"


def test_another_set_up_scales_by_particles_and_simulated_time(client):
    """No finished fill in the thesis box: the screening fill's seconds per particle-second are used, times
    the thesis fill's particles x simulated seconds, and the basis says the time steps differ."""
    screening = {"test": "fill", "fidelity": "screening", "seed": 1}
    thesis = {"test": "fill", "fidelity": "thesis", "seed": 1}
    _finish(client, _submit(client, **screening)["id"], 12.0)
    estimate = _submit(client, **thesis)["estimate"]
    assert estimate["wall_time_s"] == pytest.approx(12.0 * _size(thesis) / _size(screening))
    assert "other set-ups" in estimate["wall_time_basis"]


def test_a_hertzian_job_is_not_read_off_linear_jobs_of_its_set_up(client):
    """Hertz's time step is about 3x shorter than the linear springs' (engine.timestep): a Hertzian fill in the
    box where linear fills finished is another set-up, and a Hertzian one of the same box is the same."""
    linear = {"test": "fill", "seed": 1}
    hertz = {"test": "fill", "seed": 2, "parameters": {"effects": {"hertz_mindlin": {"young_modulus_pa": 1.0e9}}}}
    _finish(client, _submit(client, **linear)["id"], 10.0)
    estimate = _submit(client, **hertz)["estimate"]
    assert estimate["contact_law"] == "hertz_mindlin" and "other set-ups" in estimate["wall_time_basis"]
    _finish(client, _submit(client, **hertz)["id"], 30.0)
    estimate = _submit(client, **{**hertz, "seed": 3})["estimate"]
    assert estimate["wall_time_s"] == pytest.approx(30.0)
    assert estimate["wall_time_basis"] == "1 finished analytic job of the same set-up on this service"
    assert _submit(client, **{**linear, "seed": 4})["estimate"]["contact_law"] == "linear"


def test_another_evaluator_s_jobs_do_not_count(client):
    _finish(client, _submit(client, test="fill", seed=1)["id"], 5.0)
    estimate = _submit(client, test="fill", seed=2, evaluator="dem")["estimate"]
    assert estimate["wall_time_s"] is None and "no finished dem job" in estimate["wall_time_basis"]


def test_a_campaign_shows_its_battery_s_wall_time(s2):
    """The campaign estimate (a battery at the box's centre, with its targets' conditions) rests on the
    service's finished batteries of the same set-up, scaled by particles x simulated seconds."""
    client, _, _ = s2
    battery = {"test": "battery", "fidelity": "thesis", "seed": 1}
    _finish(client, _submit(client, **battery)["id"], 40.0)
    created = client.post(f"{API}/campaigns", json=campaign_body(thesis_material_id(client)))
    assert created.status_code == 201, created.text
    estimate = created.json()["estimate"]
    own = estimate["particles"] * estimate["simulated_time_s"]
    assert estimate["wall_time_s"] == pytest.approx(40.0 * own / _size(battery))
    assert estimate["wall_time_basis"] == "1 finished analytic job of the same set-up on this service"


def test_the_cli_says_the_wall_time_in_minutes_and_nothing_without_a_record():
    from service.cli_resolution import wall_time_text

    assert wall_time_text({"wall_time_s": None}) == ""
    assert wall_time_text({"wall_time_s": 300.0, "wall_time_range_s": [240.0, 360.0], "wall_time_basis": "b"}) \
        == "; about 5.0 min each here (4.0 min-6.0 min; b)"
