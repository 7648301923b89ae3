"""Direct shear test (thesis sections 3.3.2 and 4.7.2): one run per normal stress, from the precompressed fill."""
from __future__ import annotations

from engine.lab.bounds import AS_FRICTION_COEFFICIENT, SLOPE_ANGLE, STIFFEST_SOLID_PA, STRESS, Bound, Typical
from engine.lab.errors import SpecFieldError
from engine.lab.registry import ALWAYS, Bench, LabTest, Quantity, Run, StageCost
from engine.lab.stops import DST_STABILISE_MAX_S

# share of the DST's progress span spent on its own precompression when no CCT ran before it
_PRECOMPRESSION_SHARE = 0.15


def _cost(ctx, planned: frozenset[str]) -> StageCost:
    from engine.lab.cost import lid_stroke_s

    stroke_s = lid_stroke_s(ctx)
    shear_s = ctx.shear_distance_m / ctx.shear_speed_m_s
    # the preparation is the CCT's first cycle: counted here only when no CCT runs it
    precompression_s = 0.0 if "cct" in planned else 2 * stroke_s
    given = ctx.spec.options.dst_normal_stresses_pa
    more_than_preset = given is not None and len(given) > len(ctx.preset.dst_normal_stresses_pa)
    return StageCost(precompression_s + len(ctx.dst_normal_stresses_pa) * (stroke_s + DST_STABILISE_MAX_S + shear_s),
                     "options.dst_normal_stresses_pa" if more_than_preset else "options.speed_factor")


def _check(ctx) -> None:
    if max(ctx.dst_normal_stresses_pa) > ctx.cct_max_stress_pa:
        raise SpecFieldError("options.dst_normal_stresses_pa",
                             "the DST preparation compresses to the CCT maximum first, so every DST stress must be "
                             "at most options.cct_max_stress_pa")


def _run(bench: Bench, lo: float, hi: float) -> Run:
    from engine.lab.procedures.cct import precompressed_state
    from engine.lab.procedures.dst import run_dst

    ctx, fill = bench.ctx, bench.ran["fill"].outcome
    cct = bench.ran.get("cct")
    if cct is not None:
        precompressed = cct.outcome.precompressed
    else:
        split = lo + _PRECOMPRESSION_SHARE * (hi - lo)
        ctx.phase(lo, split)
        precompressed = precompressed_state(ctx, fill)
        lo = split
    dst = run_dst(ctx, precompressed, fill.packing_height_m, lo, hi)
    props, curves, psis = [], {}, []
    held = [run for run in dst.runs if run.held]  # a load not held on the servo has no values (procedures.dst)
    for run in held:
        s = run.normal_stress_target_pa
        props.append(TEST.property("residual_shear_stress_pa", run.reduction.residual_shear_stress_pa,
                                   normal_stress_pa=s))
        props.append(TEST.property("dilatancy_angle_deg", run.reduction.dilatancy_angle_deg, normal_stress_pa=s))
        psis.append(run.reduction.dilatancy_angle_deg)
        curves[f"dst_{s:.0f}"] = run.curve
    if psis:
        props.append(TEST.property("dilatancy_angle_deg", sum(psis) / len(psis)))
    if dst.fit is not None:
        props.append(TEST.property("friction_angle_deg", dst.fit.friction_angle_deg))
        props.append(TEST.property("cohesion_pa", dst.fit.cohesion_pa))
        props.append(TEST.property("mohr_coulomb_r2", dst.fit.r2))
    curves["dst_envelope"] = {
        "normal_stress_target_pa": [r.normal_stress_target_pa for r in held],
        "residual_normal_stress_pa": [r.reduction.residual_normal_stress_pa for r in held],
        "residual_shear_stress_pa": [r.reduction.residual_shear_stress_pa for r in held],
    }
    return Run(dst, props, curves)


TEST = LabTest(
    name="dst",
    title="Direct shear: residual shear stress, dilatancy, Mohr-Coulomb friction angle and cohesion",
    quantities=(
        Quantity("residual_shear_stress_pa", "Pa", STRESS, conditions=("normal_stress_pa",),
                 stress_option="dst_normal_stresses_pa"),
        # Negative dilatancy is contraction, physical for loose packings: the whole open range about zero.
        # Typical: dense sands dilate at up to about 20 deg (Bolton 1986), loose packings contract a little.
        Quantity("dilatancy_angle_deg", "deg", Bound(-90.0, 90.0, why="an angle between -90 and 90 degrees"),
                 conditions=("normal_stress_pa",), description="per load; unconditioned, the mean over the loads",
                 stress_option="dst_normal_stresses_pa",
                 typical=Typical(-10.0, 30.0, "the dilatancy angles of granular materials", "Bolton 1986")),
        # Typical: sands and gravels 27-48 deg (Das), railway ballast above 60 deg at low confinement
        # (Indraratna et al. 1998; the thesis's aggregate 60.6 deg).
        Quantity("friction_angle_deg", "deg", SLOPE_ANGLE,
                 typical=Typical(20.0, 70.0, "the friction angles of granular materials",
                                 "Das, Principles of Geotechnical Engineering; Indraratna et al. 1998",
                                 readings=(AS_FRICTION_COEFFICIENT,))),
        # A Mohr-Coulomb intercept; a fit through scattered points may put it slightly below zero.
        Quantity("cohesion_pa", "Pa", Bound(-STIFFEST_SOLID_PA, STIFFEST_SOLID_PA, why="a Mohr-Coulomb intercept")),
        Quantity("mohr_coulomb_r2", "1", Bound(0.0, 1.0, low_open=False, high_open=False,
                                               why="a coefficient of determination")),
    ),
    options=("dst_normal_stresses_pa", "cct_max_stress_pa", "shear_distance_m", "residual_window_strain",
             "moving_average_span", "speed_factor", "max_inertial_number", "inertial_number_action",
             "stop_after_reduced", "dst_speed_by_stress"),
    procedure="engine.lab.procedures.dst:run_dst",
    reducer="engine.lab.reducers.dst:reduce_dst",
    cost=_cost,
    run=_run,
    needs=("fill",),
    battery=ALWAYS,
    progress_weight=0.70,
    check=_check,
    description="From the precompressed fill (the CCT's first cycle), reload, stabilise and shear at each normal stress.",
)
