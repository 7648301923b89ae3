"""Confined compression test (thesis sections 3.4 and 4.6.2): load-unload cycles of the lid on the fill."""
from __future__ import annotations

from engine.lab.bounds import POSITIVE, STIFFEST_SOLID_PA, Bound, Typical
from engine.lab.registry import ALWAYS, Bench, LabTest, Quantity, Run, StageCost


def _cost(ctx, planned: frozenset[str]) -> StageCost:
    from engine.lab.cost import lid_stroke_s
    from engine.lab.stops import DST_STABILISE_MAX_S, UNLOAD_RELOAD_MAX_S

    cycles = ctx.spec.options.cct_cycles
    more_than_preset = cycles is not None and cycles > ctx.preset.cct_cycles
    loops = ctx.spec.options.cct_unload_reload_stresses_pa or []
    # the unload-reload's loading (one stroke at most), and per stress its hold and its slow unloading
    loops_s = (lid_stroke_s(ctx) + len(loops) * (DST_STABILISE_MAX_S + UNLOAD_RELOAD_MAX_S)) if loops else 0.0
    field = ("options.cct_unload_reload_stresses_pa" if loops else
             "options.cct_cycles" if more_than_preset else "options.speed_factor")
    return StageCost(ctx.cct_cycles * 2 * lid_stroke_s(ctx) + loops_s, field)


def _run(bench: Bench, lo: float, hi: float) -> Run:
    from engine.lab.procedures.cct import run_cct

    cct = run_cct(bench.ctx, bench.ran["fill"].outcome)
    red = cct.reduction
    props = [TEST.property("confined_modulus_pa", red.confined_modulus_pa),
             TEST.property("bulk_stiffness_n_per_m", red.bulk_stiffness_n_per_m)]
    props += [TEST.property("confined_modulus_pa", modulus, normal_stress_pa=mid)
              for mid, modulus in zip(red.window_stress_mid_pa, red.window_modulus_pa)]
    ur = cct.unload_reload
    props += [TEST.property("unload_reload_modulus_pa", modulus, normal_stress_pa=stress)
              for stress, modulus in zip(ur.stress_pa, ur.modulus_pa)]
    curves = {
        "cct": {"time_s": cct.record.time_s, "lid_z_m": cct.record.lid_z_m, "normal_strain": cct.strain.tolist(),
                "normal_stress_pa": cct.record.normal_stress_pa, "cycle": cct.record.cycle},
        "cct_modulus_vs_stress": {"normal_stress_pa": red.window_stress_mid_pa,
                                  "confined_modulus_pa": red.window_modulus_pa},
        "cct_modulus_per_cycle": {"cycle": [float(i + 1) for i in range(len(red.modulus_per_cycle_pa))],
                                  "confined_modulus_pa": red.modulus_per_cycle_pa},
    }
    if ur.stress_pa:
        curves["cct_unload_reload_modulus_vs_stress"] = {"normal_stress_pa": ur.stress_pa,
                                                         "unload_reload_modulus_pa": ur.modulus_pa}
    return Run(cct, props, curves)


TEST = LabTest(
    name="cct",
    title="Confined compression: confined modulus and bulk stiffness",
    quantities=(
        Quantity("confined_modulus_pa", "Pa", Bound(0.0, STIFFEST_SOLID_PA, high_open=False,
                                                    why="below diamond's modulus"),
                 conditions=("normal_stress_pa",), stress_option="cct_window_stresses_pa",
                 description="mean of cycles 2..N; with normal_stress_pa, the tangent E' at that stress",
                 # loose sand 10-19 MPa, dense sand 48-77 MPa (Domenico & Mifflin 1965), the thesis's
                 # aggregate 8.69 MPa: a decade of room on both sides
                 typical=Typical(1.0e6, 1.0e9, "the confined moduli of granular packings",
                                 "Domenico & Mifflin 1965")),
        # the elastic (unloading) stiffness of the packing at a stress: 2-4 x the loading E' in granular soils
        # (the Hardening Soil model's default E_ur = 3 E_50, Schanz et al. 1999)
        Quantity("unload_reload_modulus_pa", "Pa", Bound(0.0, STIFFEST_SOLID_PA, high_open=False,
                                                         why="below diamond's modulus"),
                 conditions=("normal_stress_pa",), stress_option="cct_unload_reload_stresses_pa",
                 description="E_ur at that stress: the slope of a slow unloading by a tenth of the stress, after "
                             "the cycles (options.cct_unload_reload_stresses_pa)",
                 typical=Typical(1.0e6, 3.0e9, "the unload-reload moduli of granular packings",
                                 "Schanz et al. 1999")),
        Quantity("bulk_stiffness_n_per_m", "N/m", POSITIVE, apparatus=("shear_box", "fill"),
                 derived_from=("confined_modulus_pa",),
                 relation="k = E' A / H, the container's area over the packing's height"),
    ),
    options=("cct_max_stress_pa", "cct_cycles", "cct_window_stresses_pa", "cct_unload_reload_stresses_pa",
             "speed_factor", "max_inertial_number",
             "inertial_number_action", "stop_after_reduced"),
    procedure="engine.lab.procedures.cct:run_cct",
    reducer="engine.lab.reducers.cct:reduce_cct",
    cost=_cost,
    run=_run,
    needs=("fill",),
    battery=ALWAYS,
    progress_weight=0.18,
    description="Lid cycles to the CCT maximum stress on the filled packing; its first cycle is the DST's preparation.",
)
