"""A DST load the packing does not come to rest at on the servo gives no values (procedures.dst).

The loads' values are keyed by their target normal stress; a load the servo did not bring the lid to (more
than 10 % off at the end of stabilising) would be read at another stress (hertz_strong's E 4 GPa corners read 1.2 Pa of residual shear at
"52.4 kPa"). The sequence is checked with the servo's verdict and the shearing replaced: which loads are
sheared, what the battery reports, and that the Mohr-Coulomb line goes through the loads that held. Those
are given on a known line tau = c + sigma tan(phi) (c 2 kPa, phi 40 deg), so the fit must return it exactly.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from engine.lab.context import RunContext
from engine.lab.reducers.dst import DstReduction
from engine.lab.spec import JobSpec

COHESION_PA = 2000.0
FRICTION_ANGLE_DEG = 40.0
NOT_HELD = (1, 3)  # the second and fourth of the preset's four loads


class _Sim:
    """The lid after stabilising: at ``stress_pa`` over the preset's container area."""

    def __init__(self, stress_pa: float, area_m2: float):
        self.force_n = stress_pa * area_m2

    def set_wall_servo(self, *a, **k):
        pass

    def wall_force(self, name):
        return (0.0, 0.0, self.force_n)


def _line(sigma_pa: float) -> float:
    return COHESION_PA + sigma_pa * math.tan(math.radians(FRICTION_ANGLE_DEG))


def test_a_load_the_lid_never_reached_is_not_sheared_and_says_so(monkeypatch):
    from engine.lab.procedures import dst

    ctx = RunContext.from_spec(JobSpec(test="dst", fidelity="screening", seed=1))
    area = ctx.preset.container_area_m2
    monkeypatch.setattr(dst.labsim, "restore", lambda checkpoint: _Sim(0.0, area))  # the lid at zero stress
    monkeypatch.setattr(dst, "load_to", lambda *a, **k: None)
    monkeypatch.setattr(dst, "stabilise", lambda ctx, sim, target, phase: False)
    run = dst.run_one(ctx, {}, 0.3, 52.4e3)  # a shearing would need the simulation this stand-in is not
    assert not run.held and run.reduction is None
    (warning,) = [w for w in ctx.warnings if "not sheared" in w]
    assert warning.startswith("dst 52.4 kPa")


def test_a_load_at_its_stress_with_the_packing_still_moving_a_little_is_sheared(monkeypatch):
    """Only the stress decides: 5 % off, within the servo's own scatter while shearing, the shearing starts
    (here the stand-in then stops it: it has no walls to move)."""
    from engine.lab.procedures import dst

    ctx = RunContext.from_spec(JobSpec(test="dst", fidelity="screening", seed=1))
    area = ctx.preset.container_area_m2
    assert dst.LOAD_NOT_REACHED_FRACTION == pytest.approx(0.10)
    monkeypatch.setattr(dst.labsim, "restore", lambda checkpoint: _Sim(0.95 * 52.4e3, area))
    monkeypatch.setattr(dst, "load_to", lambda *a, **k: None)
    monkeypatch.setattr(dst, "stabilise", lambda ctx, sim, target, phase: False)
    with pytest.raises(AttributeError):  # past the check: the shearing asks the stand-in for its walls
        dst.run_one(ctx, {}, 0.3, 52.4e3)
    assert not [w for w in ctx.warnings if "not sheared" in w]


def test_the_battery_reports_the_loads_that_held_and_fits_their_line(monkeypatch):
    from engine.lab.labtests import dst as labtest
    from engine.lab.procedures import dst

    stresses = RunContext.from_spec(JobSpec(test="dst", fidelity="screening", seed=1)).dst_normal_stresses_pa
    assert len(stresses) == 4
    not_held = {stresses[i] for i in NOT_HELD}

    def run_one(ctx, precompressed, height, target):
        if target in not_held:
            return dst.DstRun(target, None, {})
        red = DstReduction(_line(target), target, 5.0, np.zeros(1), np.zeros(1))
        return dst.DstRun(target, red, {"shear_strain": [0.0]})

    monkeypatch.setattr(dst, "run_one", run_one)

    class _Bench:
        ctx = RunContext.from_spec(JobSpec(test="dst", fidelity="screening", seed=1))
        ran = {"fill": type("R", (), {"outcome": type("F", (), {"packing_height_m": 0.3})()})(),
               "cct": type("R", (), {"outcome": type("C", (), {"precompressed": {}})()})()}

    run = labtest._run(_Bench(), 0.0, 1.0)
    by = {(p["quantity"], (p.get("condition") or {}).get("normal_stress_pa")): p["value"]
          for p in (q.model_dump() if hasattr(q, "model_dump") else q for q in run.properties)}
    reported = {s for (q, s) in by if q == "residual_shear_stress_pa"}
    assert reported == set(stresses) - not_held
    assert by[("friction_angle_deg", None)] == pytest.approx(FRICTION_ANGLE_DEG)
    assert by[("cohesion_pa", None)] == pytest.approx(COHESION_PA)
    assert by[("dilatancy_angle_deg", None)] == pytest.approx(5.0)
    assert run.curves["dst_envelope"]["normal_stress_target_pa"] == sorted(set(stresses) - not_held)
