"""Plausibility warnings (engine.lab.plausibility) from the typical ranges declared beside the bounds.

The numbers are the unit slips of issue 31 against the ranges of docs/lab.md, "Plausible ranges", not
outputs of our code: a confined modulus of 8.69 MPa (the thesis aggregate; sands 10-77 MPa, Domenico &
Mifflin 1965) typed as 8,690 Pa; a bulk density of 1.3967 g/cm3 typed as kg/m3 (dry bulk solids 50-4,000
kg/m3); a DST at 24 kPa typed as 24 Pa (shear tests of bulk solids run at kPa, ASTM D6128/D3080); a friction
angle typed as its coefficient 0.9 (= 42.0 deg, sands and gravels 27-48 deg, Das); a particle density of 2.6
g/cm3 typed as kg/m3 (quartz 2,650 kg/m3, CRC); contact stiffnesses of 1-3 kN/m typed as N/m (the thesis's
1.72 MN/m).
"""
import json
import math
from pathlib import Path

import pytest

from engine.lab.bounds import CONDITION_TYPICAL
from engine.lab.plausibility import (factor_warnings, measurement_warnings, options_warnings, parameter_warnings,
                                     record_warnings, settings_warnings)
from engine.lab import registry
from engine.lab.spec import MicroParameters
from engine.lab.spec import TestOptions as LabTestOptions  # not "Test*": pytest would try to collect it
from engine.lab.units import to_si

BUNDLED = Path(__file__).resolve().parents[2] / "service" / "materials" / "thesis_coarse_aggregate.json"


def _one(warnings: list[str]) -> str:
    assert len(warnings) == 1, warnings
    return warnings[0]


def test_a_kpa_modulus_typed_as_pa_names_kpa():
    text = _one(measurement_warnings("cct", "confined_modulus_pa", [8690.0]))
    assert "8,690 Pa is below the confined moduli of granular packings" in text
    assert "was it kPa, 1,000 times more (8.69e+06 Pa)?" in text


def test_a_pa_modulus_entered_with_kpa_names_pa():
    # 8,600,000 typed with --unit kPa: 8.6 GPa stored, 8.6 MPa meant
    text = _one(measurement_warnings("cct", "confined_modulus_pa", [8.6e9], input_unit="kPa"))
    assert "above the confined moduli" in text and "was it Pa, 1,000 times less" in text


def test_a_g_per_cm3_bulk_density_names_g_per_cm3():
    text = _one(measurement_warnings("fill", "bulk_density_kg_m3", [1.3967]))
    assert "1.3967 kg/m3 is below the bulk densities of dry granular materials" in text
    assert "was it g/cm3 or t/m3, 1,000 times more (1,397 kg/m3)" in text


def test_a_dst_normal_stress_typed_in_pa_names_kpa():
    text = _one(measurement_warnings("dst", "residual_shear_stress_pa", [16.2e3], {"normal_stress_pa": 24.0},
                                     measurement_id=4))
    assert text.startswith("measurement 4 (dst residual_shear_stress_pa) condition normal_stress_pa = 24 Pa is below")
    assert "was it kPa, 1,000 times more (24,000 Pa)" in text


def test_a_friction_coefficient_typed_as_an_angle_is_named():
    text = _one(measurement_warnings("dst", "friction_angle_deg", [0.9]))
    expected = math.degrees(math.atan(0.9))  # 41.99 deg
    assert f"a friction coefficient, the tangent of the angle ({expected:.2f} deg)" in text
    assert "or rad (51.57 deg)" in text  # 0.9 rad, also a friction angle of a granular material


def test_a_decimal_comma_split_replicate_is_named_by_its_position():
    # "1397,8" read as two replicates: the mean 702.5 is plausible, the 8 kg/m3 is not
    text = _one(measurement_warnings("fill", "bulk_density_kg_m3", [1397.0, 8.0]))
    assert text.startswith("fill bulk_density_kg_m3, value 2 = 8 kg/m3 is below")


def test_a_particle_density_in_g_per_cm3_on_a_job_names_g_per_cm3():
    text = _one(parameter_warnings({"particle_density_kg_m3": 2.6}))
    assert text.startswith("parameters.particle_density_kg_m3 = 2.6 kg/m3 is below the solid densities of grains")
    assert "was it g/cm3 or t/m3, 1,000 times more (2,600 kg/m3)" in text


def test_a_stiffness_range_in_kn_per_m_names_kn_per_m_at_both_ends():
    low, high = factor_warnings([{"name": "particle_stiffness_n_per_m", "low": 1e3, "high": 3e3}])
    assert "factors[0] particle_stiffness_n_per_m low = 1,000 N/m" in low and "was it kN/m" in low
    assert "factors[0] particle_stiffness_n_per_m high = 3,000 N/m" in high and "was it kN/m" in high


def test_dst_stresses_typed_in_pa_are_named_in_options_and_settings():
    assert len(options_warnings({"dst_normal_stresses_pa": [10.5, 24.0, 38.3, 52.4]})) == 4
    warnings = settings_warnings({"factors": [{"name": "friction_pp", "low": 0.3, "high": 1.0}],
                                  "fixed_parameters": {"wall_stiffness_n_per_m": 1e4 / 2},
                                  "options": {"cct_max_stress_pa": 65.6}})
    assert [w.split(" = ")[0] for w in warnings] == ["fixed_parameters.wall_stiffness_n_per_m",
                                                     "options.cct_max_stress_pa"]


def test_the_thesis_measurements_and_the_default_parameters_raise_no_warning():
    """A real material and the thesis's calibrated set are plausible: the ranges do not cry wolf."""
    data = json.loads(BUNDLED.read_text())
    for m in data["measurements"]:
        q = registry.quantity(m["test"], m["quantity"])
        values = [to_si(v, m.get("unit") or q.unit, q.unit) for v in m["values"]]
        assert measurement_warnings(m["test"], m["quantity"], values, m.get("condition")) == [], m
    assert parameter_warnings(MicroParameters().model_dump()) == []
    assert options_warnings({"dst_normal_stresses_pa": data["direct_estimates"]["dst_normal_stresses_pa"],
                             "cct_max_stress_pa": data["direct_estimates"]["cct_max_normal_stress_pa"]}) == []


def test_replicates_that_all_slipped_give_one_warning_on_their_mean():
    text = _one(measurement_warnings("fill", "bulk_density_kg_m3", [1.412, 1.3836, 1.3978], measurement_id=2))
    assert text.startswith("measurement 2 (fill bulk_density_kg_m3, mean of 3 replicates) = 1.3978 kg/m3 is below")


def test_loop_records_carry_the_input_unit_into_the_warning():
    from calibration.records import Measured

    record = Measured.from_record({"test": "cct", "quantity": "confined_modulus_pa", "condition": {},
                                   "values": [8.6e9], "unit": "Pa", "input_unit": "kPa", "id": 3})
    text = _one(record_warnings([record]))
    assert text.startswith("measurement 3 (cct confined_modulus_pa)") and "was it Pa" in text


@pytest.mark.parametrize("test_name", list(registry.tests()))
def test_every_typical_range_lies_inside_its_bound(test_name):
    for q in registry.tests()[test_name].quantities:
        if q.typical is not None:
            assert q.typical.low < q.typical.high
            assert q.bound.contains(q.typical.low) and q.bound.contains(q.typical.high), q.name


def test_micro_parameter_and_condition_ranges_lie_inside_their_bounds():
    for model in (MicroParameters, LabTestOptions):
        for name, field in model.model_fields.items():
            for typical in (m for m in field.metadata if hasattr(m, "what")):
                # the field's own bound refuses what lies outside it: the typical ends must pass it
                for end in (typical.low, typical.high):
                    value = [end, end * 1.01] if name == "dst_normal_stresses_pa" else end
                    model.model_validate({name: value})
    assert set(CONDITION_TYPICAL) <= {c for t in registry.tests().values() for q in t.quantities for c in q.conditions}
