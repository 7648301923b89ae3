"""RunContext.stages: the per-stage breakdown bench/lab.py --battery prints (issue 34)."""
import pytest

from engine.lab.context import RunContext
from engine.lab.spec import JobSpec


def test_each_report_charges_what_ran_since_the_previous_one_to_its_phase():
    ctx = RunContext.from_spec(JobSpec())
    ctx.count(100, 800, 1e-5)
    ctx.report(0.5, "fill: rainfall and settling")
    ctx.count(50, 800, 1e-5)
    ctx.report(1.0, "fill: rainfall and settling")
    ctx.count(30, 700, 2e-5)
    ctx.report(0.1, "cct: cycle 1 loading")
    fill, cct = ctx.stages["fill: rainfall and settling"], ctx.stages["cct: cycle 1 loading"]
    assert (fill.steps, fill.particle_steps) == (150, 150 * 800)
    assert fill.simulated_time_s == pytest.approx(150 * 1e-5)
    assert (cct.steps, cct.particle_steps) == (30, 30 * 700)
    assert cct.simulated_time_s == pytest.approx(30 * 2e-5)
    assert list(ctx.stages) == ["fill: rainfall and settling", "cct: cycle 1 loading"]  # order of first report
    assert sum(s.steps for s in ctx.stages.values()) == ctx.steps
    assert sum(s.wall_time_s for s in ctx.stages.values()) <= ctx.wall_time_s
