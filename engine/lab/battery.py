"""``run_job``: one test or the battery fill -> CCT -> DST (-> angle of repose, anchor pull-out).

Each test reuses what the thesis reused: the CCT and every DST start from the filled packing, and
the DST's precompression (load to the CCT maximum, unload) is the CCT's first cycle.
"""
from __future__ import annotations

import engine
from engine.lab.context import RunContext
from engine.lab.result import QUANTITIES, BulkProperty, LabResult, Provenance
from engine.lab.spec import JobSpec

# share of the progress bar per test, roughly their cost at screening fidelity
_WEIGHTS = {"fill": 0.12, "cct": 0.18, "dst": 0.70, "aor": 0.35, "anchor": 0.35}


def _prop(test: str, quantity: str, value: float, **condition: float) -> BulkProperty:
    return BulkProperty(test=test, quantity=quantity, value=float(value), unit=QUANTITIES[test][quantity],
                        condition={k: float(v) for k, v in condition.items()})


def _tests(spec: JobSpec) -> list[str]:
    if spec.test != "battery":
        return [spec.test]
    tests = ["fill", "cct", "dst"]
    if spec.options.include_aor:
        tests.append("aor")
    if spec.options.include_anchor:
        tests.append("anchor")
    return tests


def run_job(spec: JobSpec, progress=None, should_cancel=None) -> LabResult:
    """Run the spec's test (or battery); raises ``engine.lab.Cancelled`` when ``should_cancel()`` is true."""
    return run_in_context(RunContext.from_spec(spec, progress, should_cancel))


def run_in_context(ctx: RunContext) -> LabResult:
    """``run_job`` with a caller-owned context (benchmarks read its particle-step counters)."""
    from engine.lab.procedures.cct import precompressed_state, run_cct
    from engine.lab.procedures.dst import run_dst
    from engine.lab.procedures.fill import run_fill

    spec = ctx.spec
    ctx.validate()
    tests = _tests(spec)
    total = sum(_WEIGHTS[t] for t in tests)
    spans, acc = {}, 0.0
    needs_fill = any(t in ("fill", "cct", "dst") for t in tests)
    for t in tests:
        w = _WEIGHTS[t] / total
        spans[t] = (acc, acc + w)
        acc += w
    props: list[BulkProperty] = []
    curves: dict[str, dict[str, list[float]]] = {}

    fill = None
    if needs_fill:
        ctx.phase(*spans.get("fill", (0.0, spans[tests[0]][0] or 0.1)))
        fill = run_fill(ctx)
        curves.update(fill.curves)
        if "fill" in tests:
            props += [_prop("fill", q, v) for q, v in fill.properties.items()]

    precompressed = None
    if "cct" in tests:
        ctx.phase(*spans["cct"])
        cct = run_cct(ctx, fill)
        precompressed = cct.precompressed
        red = cct.reduction
        props.append(_prop("cct", "confined_modulus_pa", red.confined_modulus_pa))
        props.append(_prop("cct", "bulk_stiffness_n_per_m", red.bulk_stiffness_n_per_m))
        for mid, mod in zip(red.window_stress_mid_pa, red.window_modulus_pa):
            props.append(_prop("cct", "confined_modulus_pa", mod, normal_stress_pa=mid))
        curves["cct"] = {"time_s": cct.record.time_s, "lid_z_m": cct.record.lid_z_m,
                         "normal_strain": cct.strain.tolist(), "normal_stress_pa": cct.record.normal_stress_pa,
                         "cycle": cct.record.cycle}
        curves["cct_modulus_vs_stress"] = {"normal_stress_pa": red.window_stress_mid_pa,
                                           "confined_modulus_pa": red.window_modulus_pa}
        curves["cct_modulus_per_cycle"] = {"cycle": [float(i + 1) for i in range(len(red.modulus_per_cycle_pa))],
                                           "confined_modulus_pa": red.modulus_per_cycle_pa}

    if "dst" in tests:
        lo, hi = spans["dst"]
        if precompressed is None:
            ctx.phase(lo, lo + 0.15 * (hi - lo))
            precompressed = precompressed_state(ctx, fill)
            lo = lo + 0.15 * (hi - lo)
        dst = run_dst(ctx, precompressed, fill.packing_height_m, lo, hi)
        psis = []
        for run in dst.runs:
            s = run.normal_stress_target_pa
            props.append(_prop("dst", "residual_shear_stress_pa", run.reduction.residual_shear_stress_pa,
                               normal_stress_pa=s))
            props.append(_prop("dst", "dilatancy_angle_deg", run.reduction.dilatancy_angle_deg, normal_stress_pa=s))
            psis.append(run.reduction.dilatancy_angle_deg)
            curves[f"dst_{s:.0f}"] = run.curve
        props.append(_prop("dst", "dilatancy_angle_deg", sum(psis) / len(psis)))
        if dst.fit is not None:
            props.append(_prop("dst", "friction_angle_deg", dst.fit.friction_angle_deg))
            props.append(_prop("dst", "cohesion_pa", dst.fit.cohesion_pa))
            props.append(_prop("dst", "mohr_coulomb_r2", dst.fit.r2))
        curves["dst_envelope"] = {
            "normal_stress_target_pa": [r.normal_stress_target_pa for r in dst.runs],
            "residual_normal_stress_pa": [r.reduction.residual_normal_stress_pa for r in dst.runs],
            "residual_shear_stress_pa": [r.reduction.residual_shear_stress_pa for r in dst.runs],
        }

    if "aor" in tests:
        from engine.lab.procedures.repose import run_aor

        ctx.phase(*spans["aor"])
        aor = run_aor(ctx)
        props.append(_prop("aor", "angle_of_repose_deg", aor.reduction.angle_of_repose_deg))
        for k, angle in enumerate(aor.reduction.sector_angles_deg):
            if angle == angle:  # sectors without a measurable flank are left out
                props.append(_prop("aor", "angle_of_repose_deg", angle, sector=k + 1))
        curves.update(aor.curves)

    if "anchor" in tests:
        from engine.lab.procedures.anchor import run_anchor

        ctx.phase(*spans["anchor"])
        anc = run_anchor(ctx)
        props.append(_prop("anchor", "peak_pull_force_n", anc.reduction.peak_pull_force_n,
                           packing_height_m=anc.packing_height_m, pull_speed_m_s=anc.pull_speed_m_s))
        curves["anchor"] = anc.curve

    ctx.phase(0.0, 1.0)
    ctx.report(1.0, "done")
    return LabResult(
        test=spec.test,
        properties=props,
        curves=curves,
        provenance=Provenance(
            parameters=spec.parameters.model_dump(), seed=spec.seed, fidelity=spec.fidelity,
            engine_version=engine.__version__, steps=ctx.steps, simulated_time_s=ctx.simulated_time_s,
            wall_time_s=ctx.wall_time_s, max_inertial_number=ctx.max_inertial_number, warnings=ctx.warnings,
        ),
    )
