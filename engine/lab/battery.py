"""``run_job``: one test, or the battery fill -> CCT -> DST (-> angle of repose, anchor pull-out).

What runs comes from the lab-test registry (``engine.lab.registry.plan``): the requested tests and what they
need first, in registry order. Each test reuses what the thesis reused: the CCT and every DST start from the
filled packing, and the DST's precompression (load to the CCT maximum, unload) is the CCT's first cycle.
"""
from __future__ import annotations

import engine
from engine.lab.context import RunContext
from engine.lab.registry import Bench, plan
from engine.lab.resolution import label
from engine.lab.result import BulkProperty, LabResult, Provenance
from engine.lab.spec import JobSpec


def run_job(spec: JobSpec, progress=None, should_cancel=None) -> LabResult:
    """Run the spec's test (or battery); raises ``engine.lab.Cancelled`` when ``should_cancel()`` is true."""
    return run_in_context(RunContext.from_spec(spec, progress, should_cancel))


def run_in_context(ctx: RunContext) -> LabResult:
    """``run_job`` with a caller-owned context (benchmarks read its particle-step counters).

    A test run only because another needs it (the fill before a lone CCT) adds its curves, not its
    properties; the progress bar is split by the tests' declared weights."""
    spec = ctx.spec
    ctx.validate()
    steps = plan(spec)
    total = sum(test.progress_weight for test, _ in steps)
    bench = Bench(ctx)
    props: list[BulkProperty] = []
    curves: dict[str, dict[str, list[float]]] = {}
    lo = 0.0
    for test, reported in steps:
        hi = lo + test.progress_weight / total
        ctx.phase(lo, hi)
        run = test.run(bench, lo, hi)
        bench.ran[test.name] = run
        curves.update(run.curves)
        if reported:
            props += run.properties
        lo = hi

    ctx.phase(0.0, 1.0)
    ctx.report(1.0, "done")
    return LabResult(
        test=spec.test,
        properties=props,
        curves=curves,
        provenance=Provenance(
            parameters=spec.parameters.model_dump(), seed=spec.seed, fidelity=label(spec.resolution, spec.fidelity),
            rig=ctx.preset.rig_name, scale_factor=ctx.preset.scale_factor, engine_version=engine.__version__, steps=ctx.steps, simulated_time_s=ctx.simulated_time_s,
            wall_time_s=ctx.wall_time_s, max_inertial_number=ctx.max_inertial_number, warnings=ctx.warnings,
        ),
    )
