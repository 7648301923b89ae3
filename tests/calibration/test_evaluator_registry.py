"""The evaluator registry: declarations checked at registration, one job and a batch run the same
function, unknown names and uncovered tests refused with the choices, pydantic fields validated
against whatever is registered when they validate."""
from __future__ import annotations

import re

import pytest
from pydantic import BaseModel, ValidationError

from calibration import evaluator_registry as registry
from calibration.evaluator_registry import (ANALYTIC, DEM, LAB_TESTS, REGISTRY, Backend, EvaluatorName,
                                            UncoveredTest, UnknownEvaluator)
from engine.lab.spec import JobSpec


def test_the_declared_backends_in_order_with_the_tests_they_run():
    assert registry.names()[:2] == [DEM.name, ANALYTIC.name] == ["dem", "analytic"]
    for backend in REGISTRY.values():
        assert backend.title and backend.description
        assert set(backend.tests) <= set(LAB_TESTS)
        assert len(backend.name) <= registry.NAME_MAX


@pytest.mark.parametrize("change, message", [
    ({"name": "dem"}, "already registered"),
    ({"name": "x" * 17}, "1 to 16 characters"),
    ({"name": ""}, "1 to 16 characters"),
    ({"tests": ("triaxial",)}, "declares tests ['triaxial']"),
    ({"tests": ()}, "declares tests []"),
    ({"runner": "calibration.standin_job.run_analytic"}, "not 'module:function'"),
])
def test_a_bad_declaration_is_refused_at_registration(change, message):
    fields = {"name": "new", "title": "t", "description": "d", "tests": ("dst",),
              "runner": "calibration.standin_job:run_analytic", **change}
    with pytest.raises(ValueError, match=re.escape(message)):
        registry.register(Backend(**fields))
    assert "new" not in REGISTRY


def test_an_unknown_name_is_refused_with_the_choices(shear_only):
    with pytest.raises(UnknownEvaluator, match=re.escape("unknown evaluator 'magic'; choose one of "
                                                         "['dem', 'analytic', 'shear-only']")):
        registry.run_job("magic", JobSpec())


def test_a_batch_runs_what_a_queued_job_runs():
    """The batch contract and the workers' one-job call go through the same declaration: same
    parameters, seed and options, the same records."""
    options = {"dst_normal_stresses_pa": [5e3, 15e3]}
    batch = ANALYTIC.batch(fidelity="screening", options=options)
    requests = [({"friction_pp": 0.4}, 3), ({"friction_pp": 0.9, "particle_density_kg_m3": 2600.0}, 7)]
    records = batch(requests)
    assert batch.runs == 2
    for (parameters, seed), got in zip(requests, records):
        job = registry.run_job("analytic", JobSpec(seed=seed, fidelity="screening", parameters=parameters,
                                                   options=options))
        assert got == [p.model_dump() for p in job.properties]
    loads = {r["condition"]["normal_stress_pa"] for r in records[0] if r["quantity"] == "residual_shear_stress_pa"}
    assert loads == {5e3, 15e3}


def test_a_registered_backend_runs_only_the_tests_it_declares(shear_only):
    result = registry.run_job("shear-only", JobSpec(test="dst", seed=1))
    assert {p.test for p in result.properties} == {"dst"}
    with pytest.raises(UncoveredTest, match=re.escape("'shear-only' does not run test 'cct'; it runs ['dst']")):
        registry.run_job("shear-only", JobSpec(test="cct"))
    with pytest.raises(UncoveredTest):
        shear_only.batch(test="battery")([({}, 0)])


class _Body(BaseModel):
    evaluator: EvaluatorName = DEM.name


def test_pydantic_fields_validate_against_the_registry_when_they_validate(shear_only):
    assert _Body(evaluator="shear-only").evaluator == "shear-only"
    with pytest.raises(ValidationError) as caught:
        _Body(evaluator="python")
    (error,) = caught.value.errors()
    assert error["loc"] == ("evaluator",) and "choose one of ['dem', 'analytic', 'shear-only']" in error["msg"]
    schema = _Body.model_json_schema()["properties"]["evaluator"]
    assert schema["enum"] == ["dem", "analytic", "shear-only"] and schema["default"] == "dem"
