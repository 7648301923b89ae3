"""The notebook loop leaves out what its runs cannot be compared with, as a campaign does (issue 29): one
rule (``calibration.comparable.split``) for both drivers, named in every report, never compared silently."""
from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from calibration.loop import CalibrationLoop
from calibration.records import Measured
from engine.lab.rigs import bundled_rig
from engine.particles.description import Particles

ROOT = Path(__file__).resolve().parents[2]
BUNDLED = json.loads((ROOT / "service" / "materials" / "thesis_coarse_aggregate.json").read_text())
MEASURED_IN_THE_BOX = {("fill", "bulk_density_kg_m3"), ("fill", "bulk_mass_kg"), ("dst", "friction_angle_deg")}
FACTORS = [{"name": "particle_density_kg_m3", "low": 2300.0, "high": 2700.0},
           {"name": "friction_pp", "low": 0.3, "high": 1.0}]


def _targets() -> list[Measured]:
    return [Measured.from_record(m) for m in BUNDLED["measurements"] if (m["test"], m["quantity"]) in MEASURED_IN_THE_BOX]


def _loop(**settings) -> CalibrationLoop:
    return CalibrationLoop.on_backend(
        _targets(), "analytic", {"factors": FACTORS, "design": {"type": "full", "centre_runs": 2}, "diagnose": False,
                                 "polish_steps": 0, **settings},
        measured_rig=bundled_rig(BUNDLED["rig"]), measured_particles=Particles.model_validate(BUNDLED["particles"]))


def test_in_the_400_mm_preset_the_590_mm_box_s_bulk_mass_is_left_out_naming_both_rigs():
    loop = _loop(fidelity="screening")
    assert [(t["test"], t["quantity"]) for t in loop.left_out_targets] == [("fill", "bulk_mass_kg")]
    reason = loop.left_out_targets[0]["reason"]
    assert "thesis-590mm-shear-box" in reason and "appendix-a-400mm-shear-box" in reason
    report = loop.run().first.report
    assert [(t["test"], t["quantity"]) for t in report["left_out_targets"]] == [("fill", "bulk_mass_kg")]
    assert "bulk_mass_kg" not in {r["quantity"] for r in report["targets"]}


def test_coarse_in_the_measurements_own_rig_counts_the_fill_once():
    """At a material resolution the loop runs in the measurements' rig (copied into its settings, as a campaign
    copies its material's): nothing is left out for the apparatus, and the packing is struck off at the box's
    330 mm level as the laboratory did, so the bulk mass is the bulk density times pi (0.295 m)^2 x 0.330 m
    (thesis Eq. 4.2), the same weighing: it is left out as computed from the bulk density, not counted twice."""
    loop = _loop(resolution={"mode": "coarse", "scale_factor": 1.3})
    assert [(t["test"], t["quantity"]) for t in loop.left_out_targets] == [("fill", "bulk_mass_kg")]
    assert "computed from bulk_density_kg_m3 and packing_height_m" in loop.left_out_targets[0]["reason"]
    first = loop.run().first
    assert [t["quantity"] for t in first.report["left_out_targets"]] == ["bulk_mass_kg"]
    rows = {r["quantity"]: r for r in first.report["targets"]}
    assert set(rows) == {"bulk_density_kg_m3", "friction_angle_deg"}
    assert rows["bulk_density_kg_m3"]["status"] == "modelled"


def test_the_fill_is_one_measurement_however_many_ways_it_is_reported():
    """The bundled material's fill reports bulk density, porosity, voids ratio, packing height and bulk mass
    (Table 4.5): one weighing and one reading. Porosity and voids ratio are exact functions of the bulk density
    and the solid density (Eqs. 4.4, 4.7), the bulk mass is rho_b A H (Eq. 4.2). Struck off at a level (a
    material resolution) the height is the rig's, so the fill enters once, as its bulk density; at the preset
    (the thesis's DEM rule, its height read from the highest sphere top) the height is a reading of its own and
    the fill enters twice, bulk density and packing height."""
    fill = [Measured.from_record(m) for m in BUNDLED["measurements"] if m["test"] == "fill"]
    coarse = CalibrationLoop.on_backend(
        fill, "analytic", {"factors": FACTORS, "resolution": {"mode": "coarse", "scale_factor": 1.3}},
        measured_rig=bundled_rig(BUNDLED["rig"]), measured_particles=Particles.model_validate(BUNDLED["particles"]))
    assert [t.key.quantity for t in coarse.targets] == ["bulk_density_kg_m3"]
    reasons = {t["quantity"]: t["reason"] for t in coarse.left_out_targets}
    assert set(reasons) == {"porosity", "voids_ratio", "packing_height_m", "bulk_mass_kg"}
    assert "struck off" in reasons["packing_height_m"] and "rho_b / rho_p" in reasons["porosity"]
    preset = CalibrationLoop.on_backend(fill, "analytic", {"factors": FACTORS, "fidelity": "thesis"},
                                        measured_rig=bundled_rig(BUNDLED["rig"]),
                                        measured_particles=Particles.model_validate(BUNDLED["particles"]))
    assert sorted(t.key.quantity for t in preset.targets) == ["bulk_density_kg_m3", "packing_height_m"]


def test_a_loop_with_nothing_left_to_compare_is_refused_with_the_reasons():
    only_mass = [t for t in _targets() if t.key.quantity == "bulk_mass_kg"]
    with pytest.raises(ValueError, match="bulk_mass_kg.*thesis-590mm-shear-box"):
        CalibrationLoop.on_backend(only_mass, "analytic", {"fidelity": "screening", "factors": FACTORS},
                                   measured_rig=bundled_rig(BUNDLED["rig"]))
