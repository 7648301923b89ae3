"""The lab-test registry (issue 28, point 2): each test declared once, and what is derived from it.

No simulation runs here: the checks are on the declarations, the plan of a job, the cost model's
arithmetic (from the preset's geometry and speeds) and the errors that carry the field to change.
"""
from __future__ import annotations

import importlib
import math
from dataclasses import replace

import pytest
from pydantic import ValidationError

from engine.lab import registry
from engine.lab.context import RunContext
from engine.lab.cost import estimate
from engine.lab.errors import SpecFieldError
from engine.lab.presets import SCREENING
from engine.lab import spec as lab_spec
from engine.lab.spec import JobSpec
from engine.lab.stops import DST_STABILISE_MAX_S, LID_MAX_TRAVEL_FRACTION


def names(steps):
    return [(test.name, reported) for test, reported in steps]


def test_every_quantity_is_declared_with_a_unit_and_a_non_empty_bound():
    for test in registry.tests().values():
        for q in test.quantities:
            assert q.unit, (test.name, q.name)
            assert q.bound.low < q.bound.high, (test.name, q.name)
            assert all(c.replace("_", "").isalnum() for c in q.conditions), (test.name, q.name)


def test_bounds_are_the_definitions_of_the_quantities():
    """A porosity is a void fraction, an R^2 lies in [0, 1], a slope angle between flat and vertical."""
    porosity = registry.quantity("fill", "porosity").bound
    assert porosity.contains(0.4) and not porosity.contains(1.0) and not porosity.contains(0.0)
    r2 = registry.quantity("dst", "mohr_coulomb_r2").bound
    assert r2.contains(0.0) and r2.contains(1.0) and not r2.contains(1.0 + 1e-12)
    repose = registry.quantity("aor", "angle_of_repose_deg").bound
    assert repose.contains(35.0) and not repose.contains(90.0) and not repose.contains(math.nan)


def test_the_names_a_job_accepts_are_the_battery_then_every_test():
    assert registry.job_test_names() == [registry.BATTERY, *registry.tests()]
    assert JobSpec.model_json_schema()["properties"]["test"]["enum"] == registry.job_test_names()
    with pytest.raises(ValidationError) as info:
        JobSpec(test="shear")
    assert info.value.errors()[0]["loc"] == ("test",)


def test_every_option_is_read_by_some_test_and_every_declared_option_exists():
    read = set().union(*(t.options for t in registry.tests().values()))
    assert read == set(lab_spec.TestOptions.model_fields)


def test_procedures_and_reducers_resolve_to_functions():
    for test in registry.tests().values():
        for ref in (test.procedure, test.reducer):
            module, function = ref.split(":")
            assert callable(getattr(importlib.import_module(module), function)), ref


def test_a_lone_test_runs_after_what_it_needs_and_reports_only_itself():
    assert names(registry.plan(JobSpec(test="cct"))) == [("fill", False), ("cct", True)]
    assert names(registry.plan(JobSpec(test="aor"))) == [("aor", True)]
    battery = JobSpec(options={"include_anchor": True})
    assert names(registry.plan(battery)) == [("fill", True), ("cct", True), ("dst", True), ("anchor", True)]
    with_aor = JobSpec(options={"include_aor": True, "include_anchor": True})
    assert [t.name for t in registry.requested(with_aor)] == list(registry.tests())


def test_registration_refuses_what_would_break_a_derivation():
    fill, cct = registry.get("fill"), registry.get("cct")
    known = {"fill": fill}
    with pytest.raises(ValueError, match="not TestOptions fields"):
        registry._validate(replace(cct, options=("cct_cycle",)), known)
    with pytest.raises(ValueError, match="registered before"):
        registry._validate(replace(cct, needs=("dst",)), known)
    with pytest.raises(ValueError, match="taken"):
        registry._validate(replace(cct, name="battery"), known)
    with pytest.raises(ValueError, match="battery switch"):
        registry._validate(replace(cct, battery="include_cct"), known)


def test_a_property_carries_its_declared_unit_and_only_declared_conditions():
    dst = registry.get("dst")
    prop = dst.property("residual_shear_stress_pa", 12e3, normal_stress_pa=24e3)
    assert prop.unit == "Pa" and prop.condition == {"normal_stress_pa": 24e3}
    with pytest.raises(ValueError, match="not declared"):
        dst.property("friction_angle_deg", 30.0, normal_stress_pa=24e3)
    with pytest.raises(ValueError, match="not reported"):
        dst.property("porosity", 0.4)


def stroke_s() -> float:
    """One screening lid stroke at most: its travel limit of the packing height at lab lid speed x factor."""
    return LID_MAX_TRAVEL_FRACTION * SCREENING.packing_height_m / (
        SCREENING.lab_lid_speed_m_s * SCREENING.default_speed_factor)


def test_the_dst_counts_its_own_precompression_only_without_a_cct():
    """Alone, the DST prepares its packing with the CCT's first cycle (two strokes); in a battery the CCT ran it."""
    alone, battery = estimate(JobSpec(test="dst")), estimate(JobSpec())
    assert alone.stages_s["dst"] - battery.stages_s["dst"] == pytest.approx(2 * stroke_s())
    shear_s = SCREENING.shear_distance_m / (SCREENING.lab_shear_speed_m_s * SCREENING.default_speed_factor)
    per_load_s = stroke_s() + DST_STABILISE_MAX_S + shear_s
    assert battery.stages_s["dst"] == pytest.approx(len(SCREENING.dst_normal_stresses_pa) * per_load_s)


def test_cost_names_the_field_that_lowers_it():
    cycles = estimate(JobSpec(test="cct", options={"cct_cycles": SCREENING.cct_cycles + 1}))
    assert cycles.time_stage == "cct" and cycles.time_field == "options.cct_cycles"
    assert estimate(JobSpec(test="cct")).time_field == "options.speed_factor"
    in_battery = estimate(JobSpec(options={"include_aor": True}))
    assert in_battery.stages["aor"].particles_field == "options.include_aor"
    assert estimate(JobSpec(test="aor")).stages["aor"].particles_field == "test"


def test_lab_checks_raise_the_field_not_a_message_to_parse():
    with pytest.raises(SpecFieldError) as info:
        RunContext.from_spec(JobSpec(options={"moving_average_span": 20})).validate()
    assert info.value.field == "options.moving_average_span"
    with pytest.raises(SpecFieldError) as info:
        RunContext.from_spec(JobSpec(fidelity="thesis", parameters={"particle_radius_m": 0.02}))
    assert info.value.field == "parameters.particle_radius_m"


def test_the_dst_check_applies_where_a_dst_runs():
    """DST stresses above the CCT maximum cannot be reached by its preparation; a lone angle of repose
    never compresses, so the same options are fine there."""
    options = {"cct_max_stress_pa": 20e3, "dst_normal_stresses_pa": [10e3, 30e3]}
    for test in ("dst", "battery"):
        with pytest.raises(SpecFieldError) as info:
            RunContext.from_spec(JobSpec(test=test, options=options)).validate()
        assert info.value.field == "options.dst_normal_stresses_pa"
    RunContext.from_spec(JobSpec(test="aor", options=options)).validate()
