"""Job specs, presets, quasi-static controls and the CLI: the parts that need no simulation."""
import json
import math
from pathlib import Path

import pytest

from engine.lab import Cancelled, run_job
from engine.lab.cli import SpecError, load_spec, main
from engine.lab.context import QuasiStaticError, RunContext
from engine.lab.presets import SCREENING, THESIS, fidelity
from engine.lab.spec import JobSpec

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"


def test_screening_conditions_are_appendix_a_forces_over_the_container_area():
    area = math.pi * 0.2**2
    assert SCREENING.dst_normal_stresses_pa == pytest.approx([f / area for f in (1885, 3495, 5105, 6760)])
    assert SCREENING.cct_max_stress_pa == pytest.approx(8415 / area)
    assert THESIS.dst_normal_stresses_pa == (10.5e3, 24.0e3, 38.3e3, 52.4e3)
    assert THESIS.cct_max_stress_pa == 65.6e3
    assert THESIS.container_diameter_m == pytest.approx(0.59)


def test_particle_radius_only_at_screening():
    assert fidelity("screening", 0.025).shapes[0].radius_min_m == 0.025
    with pytest.raises(ValueError, match="screening"):
        fidelity("thesis", 0.025)


def test_examples_validate():
    files = sorted(EXAMPLES.glob("*.json")) + sorted(EXAMPLES.glob("*.yaml"))
    assert any(f.name == "screening-battery.json" for f in files)
    for f in files:
        spec = load_spec(f)
        RunContext.from_spec(spec).validate()
    battery = load_spec(EXAMPLES / "screening-battery.json")
    assert (battery.test, battery.fidelity) == ("battery", "screening")


def test_inertial_number_warns_or_refuses():
    ctx = RunContext.from_spec(JobSpec(options={"max_inertial_number": 1e-3}))
    ctx.inertial_number(5e-4, "dst/shearing")
    assert ctx.warnings == []
    ctx.inertial_number(2e-3, "dst/shearing")
    ctx.inertial_number(3e-3, "dst/shearing")
    assert len(ctx.warnings) == 1 and "speed_factor" in ctx.warnings[0]
    assert ctx.max_inertial_number == 3e-3
    strict = RunContext.from_spec(JobSpec(options={"max_inertial_number": 1e-3, "inertial_number_action": "refuse"}))
    with pytest.raises(QuasiStaticError):
        strict.inertial_number(2e-3, "cct/lid loading")


def test_speed_factor_default_and_override():
    assert RunContext.from_spec(JobSpec()).shear_speed_m_s == pytest.approx(0.001 * SCREENING.default_speed_factor)
    assert RunContext.from_spec(JobSpec(options={"speed_factor": 5})).lid_speed_m_s == pytest.approx(0.005)


@pytest.mark.parametrize("options, field", [
    ({"dst_normal_stresses_pa": [-1.0]}, "dst_normal_stresses_pa"),
    ({"shear_distance_m": 0.02}, "shear_distance_m"),
    ({"dst_normal_stresses_pa": [90e3]}, "dst_normal_stresses_pa"),
    ({"moving_average_span": 20}, "moving_average_span"),
])
def test_impossible_options_are_refused_before_simulating(options, field):
    with pytest.raises(ValueError, match=field):
        run_job(JobSpec(test="dst", options=options))


def test_cancel_before_any_work():
    with pytest.raises(Cancelled):
        run_job(JobSpec(test="fill"), should_cancel=lambda: True)


def test_cli_bad_spec_exits_2_naming_the_field(tmp_path, capsys):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"test": "battery", "options": {"cct_cycles": 0}}))
    assert main(["run", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "options.cct_cycles" in err and "Traceback" not in err
    typo = tmp_path / "typo.yaml"
    typo.write_text("test: battery\nparameters:\n  frictoin_pp: 0.5\n")
    assert main(["run", str(typo)]) == 2
    assert "parameters.frictoin_pp" in capsys.readouterr().err
    broken = tmp_path / "broken.json"
    broken.write_text("{not json")
    assert main(["run", str(broken)]) == 2
    assert "not valid JSON" in capsys.readouterr().err
    assert main(["run", str(tmp_path / "missing.json")]) == 2
    impossible = tmp_path / "impossible.json"
    impossible.write_text(json.dumps({"test": "dst", "options": {"shear_distance_m": 0.01}}))
    assert main(["run", str(impossible)]) == 2
    assert "shear_distance_m" in capsys.readouterr().err


def test_load_spec_rejects_non_mapping(tmp_path):
    f = tmp_path / "list.json"
    f.write_text("[1, 2]")
    with pytest.raises(SpecError, match="mapping"):
        load_spec(f)
