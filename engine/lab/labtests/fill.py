"""Fill (thesis section 4.5.4): rain the shear box, settle, level, settle; the packing the CCT and DST start from."""
from __future__ import annotations

from engine.lab.bounds import DENSEST_SOLID_KG_M3, POSITIVE, SQLITE_INT_MAX, Bound, Typical
from engine.lab.registry import ALWAYS, Bench, LabTest, Quantity, Run, StageCost
from engine.lab.stops import LEVEL_SETTLE_MAX_S, RAIN_SETTLE_MAX_S


def _cost(ctx, planned: frozenset[str]) -> StageCost:
    from engine.lab.cost import packing_spheres
    from engine.lab.resolution import particles_field

    preset = ctx.preset
    solids_m3 = preset.container_area_m2 * preset.packing_height_m * preset.expected_solid_fraction
    return StageCost(RAIN_SETTLE_MAX_S + LEVEL_SETTLE_MAX_S, "options.speed_factor",
                     packing_spheres(solids_m3, preset.fill_margin, preset.shapes),
                     particles_field(ctx.spec))


def _run(bench: Bench, lo: float, hi: float) -> Run:
    from engine.lab.procedures.fill import run_fill

    fill = run_fill(bench.ctx)
    return Run(fill, [TEST.property(q, v) for q, v in fill.properties.items()], fill.curves)


TEST = LabTest(
    name="fill",
    title="Fill: bulk density and porosity of the levelled packing",
    quantities=(
        # Typical: from powdered carbon (80 kg/m3) and bagasse (120) to barite and cast-iron chips (2,900-3,200)
        # in the bulk-materials tables (simetric.co.uk; inter-bulk.com).
        Quantity("bulk_density_kg_m3", "kg/m3", Bound(0.0, DENSEST_SOLID_KG_M3, high_open=False,
                                                       why="below the densest solid, osmium"),
                 typical=Typical(50.0, 4000.0, "the bulk densities of dry granular materials",
                                 "bulk-density tables of simetric.co.uk and inter-bulk.com")),
        # Typical: random close packing of spheres 0.36, random loose 0.445 (Scott & Kilgour 1969; Onoda &
        # Liniger 1990); non-spherical grains and fine powders pack looser.
        Quantity("porosity", "1", Bound(0.0, 1.0, why="a void volume fraction"),
                 typical=Typical(0.2, 0.8, "the porosities of granular packings",
                                 "Scott & Kilgour 1969; Onoda & Liniger 1990"),
                 derived_from=("bulk_density_kg_m3",), relation="n = 1 - rho_b / rho_p (thesis Eqs. 4.4, 4.7)"),
        # e = n / (1 - n): any positive number for n in (0, 1); typical, the porosities' range mapped
        Quantity("voids_ratio", "1", POSITIVE,
                 typical=Typical(0.25, 4.0, "the voids ratios of granular packings",
                                 "Scott & Kilgour 1969; Onoda & Liniger 1990"),
                 derived_from=("bulk_density_kg_m3",), relation="e = rho_p / rho_b - 1 (thesis Eq. 4.4)"),
        Quantity("packing_height_m", "m", POSITIVE, apparatus=("shear_box", "fill"), rig_value_when_struck_off=True),
        Quantity("bulk_mass_kg", "kg", POSITIVE, apparatus=("shear_box", "fill"),
                 derived_from=("bulk_density_kg_m3", "packing_height_m"),
                 relation="m = rho_b A H (thesis Eq. 4.2)"),
        Quantity("particle_count", "1", Bound(1.0, float(SQLITE_INT_MAX), low_open=False, why="a count of particles"),
                 apparatus=("shear_box", "fill"), per_particle=True),
    ),
    options=("fill_drop_height_m", "fill_friction_pp", "shear_distance_m"),  # the ring is as wide as the shear
    procedure="engine.lab.procedures.fill:run_fill",
    reducer="engine.lab.reducers.packing:bulk_properties",
    cost=_cost,
    run=_run,
    battery=ALWAYS,
    progress_weight=0.12,
    description="Rainfall into the shear box, settling, levelling at the packing height (thesis Eqs. 4.2, 4.4, 4.7).",
)
