"""The proof that an exported material behaves the same in LIGGGHTS (issue 30, item 3).

``verify_export(material, seeds)`` runs the material's LIGGGHTS include (``calibration.export.liggghts``)
on the screening rig's fill and confined compression test (``calibration.export.rig_liggghts``) and
demcal's own lab (engine/lab: the fill and CCT of the battery) at the same parameters, one packing per
seed in each engine, and compares bulk density, porosity, the mean confined modulus E' and E' per stress
window. Each difference is judged against a tolerance (bulk density and porosity 2 %, E' 10 %) or,
where the packings scatter more than that, against the difference's own scatter (twice its standard
error over the seeds). The hand-off holds when bulk density, porosity and the mean E' each pass one of
the two; E' per window is judged the same way and printed for information only (with five more 2-sigma
tests about one run in five that agrees would fail one of them).

Both engines reduce their lid records with the same function (engine.lab.reducers.cct.reduce_cct) and
measure the height the same way (highest sphere top after levelling), so only the engines and the
set-up differences listed in rig_liggghts differ.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from calibration.export.liggghts import _primes_above, render
from calibration.export.material import ExportMaterial
from calibration.export.rig_liggghts import ClumpBody, Rig, run_rig, screening_rig

BULK_TOLERANCE = 0.02
MODULUS_TOLERANCE = 0.10
SCATTER_MULTIPLE = 2.0  # a difference within twice its standard error is not distinguishable from scatter


def to_micro_parameters(material: ExportMaterial):
    """The lab's ``MicroParameters`` for the material: the screening rig takes one sphere size or one
    two-sphere clump (``clump_aspect_ratio``, engine/lab/shape.py)."""
    from engine.lab.shape import aspect_ratio_of
    from engine.lab.spec import MicroParameters

    p, c = material.particles, material.contact
    if len(p.spheres) + len(p.clumps) != 1:
        raise ValueError("verify-export runs the screening rig, which takes one sphere size or one two-sphere "
                         f"clump; this material has {len(p.spheres)} sphere size(s) and {len(p.clumps)} clump(s)")
    if p.clumps:
        template = p.clumps[0].template()
        radii = np.asarray(template.sphere_radii_m)
        if template.n_spheres != 2 or radii[0] != radii[1]:
            raise ValueError("verify-export: the screening rig's clumps are two equal spheres "
                             f"(clump_aspect_ratio); {p.clumps[0].name} has {template.n_spheres} sphere(s)")
        radius, aspect = template.equivalent_radius_m, aspect_ratio_of(template)
    else:
        radius, aspect = p.spheres[0].radius_m, 1.0
    if c.damping_ratio_normal != c.damping_ratio_shear:
        raise ValueError("verify-export: demcal's lab takes one damping ratio for both directions; the material "
                         f"has {c.damping_ratio_normal} normal and {c.damping_ratio_shear} shear")
    return MicroParameters(
        particle_density_kg_m3=p.solid_density_kg_m3, particle_stiffness_n_per_m=c.particle_stiffness_n_per_m,
        wall_stiffness_n_per_m=c.wall_stiffness_n_per_m,
        shear_to_normal_stiffness_ratio=c.shear_to_normal_stiffness_ratio, friction_pp=c.friction_pp,
        friction_pw=c.friction_pw, damping_ratio=c.damping_ratio_normal, local_damping=c.local_damping,
        particle_radius_m=radius, clump_aspect_ratio=aspect, effects=material.effects)


@dataclass
class PackingFigures:
    engine: str
    seed: int
    bulk_density_kg_m3: float
    porosity: float
    packing_height_m: float
    particle_count: int
    confined_modulus_pa: float
    window_stress_mid_pa: list[float]
    window_modulus_pa: list[float]
    wall_time_s: float


@dataclass
class Comparison:
    quantity: str
    demcal_mean: float
    demcal_sd: float
    liggghts_mean: float
    liggghts_sd: float
    difference: float  # (LIGGGHTS - demcal) / demcal
    scatter: float  # standard error of that difference, relative
    tolerance: float
    holds: bool
    gating: bool = True  # False: printed for information, not part of the verdict


@dataclass
class VerifyReport:
    material: str
    seeds: list[int]
    cct_cycles: int
    packings: list[PackingFigures] = field(default_factory=list)
    comparisons: list[Comparison] = field(default_factory=list)
    inexact: list[str] = field(default_factory=list)

    @property
    def holds(self) -> bool:
        gating = [c for c in self.comparisons if c.gating]
        return bool(gating) and all(c.holds for c in gating)

    def to_dict(self) -> dict:
        return {**asdict(self), "holds": self.holds}

    def text(self) -> str:
        lines = [f"verify-export: {self.material}, screening rig, seeds {self.seeds}, {self.cct_cycles} CCT cycles"]
        for f in self.packings:
            lines.append(f"  {f.engine:8s} seed {f.seed}: rho_b {f.bulk_density_kg_m3:8.1f} kg/m3  n {f.porosity:.4f}  "
                         f"H {f.packing_height_m * 1000:6.1f} mm  N {f.particle_count:4d}  E' {f.confined_modulus_pa / 1e6:7.3f} MPa  "
                         f"({f.wall_time_s:.0f} s)")
        lines.append(f"  {'quantity':34s} {'demcal':>20s} {'LIGGGHTS':>20s} {'diff':>7s} {'scatter':>7s} {'tol':>5s}")
        for c in self.comparisons:
            lines.append(f"  {c.quantity:34s} {c.demcal_mean:11.5g} +- {c.demcal_sd:<6.3g} {c.liggghts_mean:11.5g} +- "
                         f"{c.liggghts_sd:<6.3g} {c.difference * 100:+6.1f}% {c.scatter * 100:6.1f}% {c.tolerance * 100:4.0f}% "
                         f"{'holds' if c.holds else 'DIFFERS'}{'' if c.gating else ' (information)'}")
        for note in self.inexact:
            lines.append(f"  not exact in LIGGGHTS: {note}")
        lines.append(f"  hand-off {'HOLDS' if self.holds else 'DOES NOT HOLD'}: bulk density and porosity within "
                     f"{BULK_TOLERANCE * 100:g} %, E' (mean of cycles 2..N) within {MODULUS_TOLERANCE * 100:g} %, each "
                     f"or within {SCATTER_MULTIPLE:g} x the difference's standard error; E' per window is judged the "
                     "same way but for information (five more 2-sigma tests would fail about one agreeing run in five)")
        return "\n".join(lines)


def _demcal_packing(params, seed: int, cct_cycles: int, speed_factor: float | None) -> PackingFigures:
    from engine.lab.context import RunContext
    from engine.lab.registry import Bench, plan
    from engine.lab.spec import JobSpec, TestOptions

    spec = JobSpec(test="cct", fidelity="screening", seed=seed, parameters=params,
                   options=TestOptions(cct_cycles=cct_cycles, speed_factor=speed_factor))
    ctx = RunContext.from_spec(spec)
    ctx.validate()
    bench = Bench(ctx)
    t0 = time.monotonic()
    for test, _ in plan(spec):
        ctx.phase(0.0, 1.0)
        bench.ran[test.name] = test.run(bench, 0.0, 1.0)
    fill = {p.quantity: p.value for p in bench.ran["fill"].properties}
    red = bench.ran["cct"].outcome.reduction
    return PackingFigures("demcal", seed, fill["bulk_density_kg_m3"], fill["porosity"], fill["packing_height_m"],
                          int(fill["particle_count"]), float(red.confined_modulus_pa),
                          list(map(float, red.window_stress_mid_pa)), list(map(float, red.window_modulus_pa)),
                          time.monotonic() - t0)


def liggghts_rig_run(export, rig: Rig, params, material: ExportMaterial, seed: int, workdir: str | None):
    """LIGGGHTS' own fill and CCT of the screening rig for ``seed`` (its insertion seed a prime from it)."""
    r_equivalent = float(params.particle_radius_m)  # the volume-equivalent radius of a body
    clump = None
    r_sphere = r_equivalent
    if material.particles.clumps:
        template = material.particles.clumps[0].template()
        clump = ClumpBody(template.n_spheres, template.mass_kg(params.particle_density_kg_m3))
        r_sphere = float(np.min(template.sphere_radii_m))
    return run_rig(export, rig, _primes_above(32452843 + 7919 * seed, 1)[0], r_sphere, r_sphere,
                   2.0 * r_equivalent, workdir, clump=clump)


def _liggghts_packing(export, rig: Rig, params, material: ExportMaterial, seed: int,
                      workdir: str | None) -> PackingFigures:
    from engine.lab.reducers.packing import PackingState, bulk_properties

    run = liggghts_rig_run(export, rig, params, material, seed, workdir)
    rho = params.particle_density_kg_m3
    props = bulk_properties(PackingState(run.bulk_mass_kg / rho, rho, run.packing_height_m, rig.area_m2,
                                         run.particle_count))
    red = run.reduction(rig)
    return PackingFigures("LIGGGHTS", seed, props["bulk_density_kg_m3"], props["porosity"], run.packing_height_m,
                          run.particle_count, float(red.confined_modulus_pa),
                          list(map(float, red.window_stress_mid_pa)), list(map(float, red.window_modulus_pa)),
                          run.wall_time_s)


def _compare(name: str, d: list[float], lig: list[float], tolerance: float) -> Comparison:
    d_arr, l_arr = np.asarray(d, float), np.asarray(lig, float)
    dm, lm = float(np.mean(d_arr)), float(np.mean(l_arr))
    dsd = float(np.std(d_arr, ddof=1)) if d_arr.size > 1 else 0.0
    lsd = float(np.std(l_arr, ddof=1)) if l_arr.size > 1 else 0.0
    diff = (lm - dm) / dm
    scatter = math.sqrt(dsd ** 2 / d_arr.size + lsd ** 2 / l_arr.size) / abs(dm)
    holds = abs(diff) <= tolerance or abs(diff) <= SCATTER_MULTIPLE * scatter
    return Comparison(name, dm, dsd, lm, lsd, diff, scatter, tolerance, holds)


def verify_export(material: ExportMaterial | dict, seeds=(1, 2, 3), cct_cycles: int = 2,
                  speed_factor: float | None = None, workdir: str | None = None, progress=None) -> VerifyReport:
    """Run the export in LIGGGHTS and demcal's lab over ``seeds`` packings each and compare (see module doc).

    One engine runs at a time (the machine is shared). ``progress(message)`` is told each packing as it
    starts and its figures when it ends."""
    if not isinstance(material, ExportMaterial):
        material = ExportMaterial.model_validate(material)
    params = to_micro_parameters(material)
    export = render(material)
    rig = screening_rig(cct_cycles, speed_factor)
    report = VerifyReport(material.name, list(seeds), cct_cycles, inexact=list(export.inexact))
    for seed in seeds:
        for engine in ("demcal", "LIGGGHTS"):
            if progress:
                progress(f"{engine} seed {seed}")
            fig = (_demcal_packing(params, seed, cct_cycles, speed_factor) if engine == "demcal"
                   else _liggghts_packing(export, rig, params, material, seed, workdir))
            report.packings.append(fig)
            if progress:
                progress(f"{engine} seed {seed}: rho_b {fig.bulk_density_kg_m3:.1f} kg/m3, n {fig.porosity:.4f}, "
                         f"E' {fig.confined_modulus_pa / 1e6:.3f} MPa, windows "
                         f"{[round(m / 1e6, 3) for m in fig.window_modulus_pa]} MPa ({fig.wall_time_s:.0f} s)")
    dem = [f for f in report.packings if f.engine == "demcal"]
    lig = [f for f in report.packings if f.engine == "LIGGGHTS"]
    report.comparisons.append(_compare("bulk_density_kg_m3", [f.bulk_density_kg_m3 for f in dem],
                                       [f.bulk_density_kg_m3 for f in lig], BULK_TOLERANCE))
    report.comparisons.append(_compare("porosity", [f.porosity for f in dem], [f.porosity for f in lig], BULK_TOLERANCE))
    report.comparisons.append(_compare("confined_modulus_pa (cycles 2..N)", [f.confined_modulus_pa for f in dem],
                                       [f.confined_modulus_pa for f in lig], MODULUS_TOLERANCE))
    n_windows = min(len(f.window_modulus_pa) for f in report.packings)
    for k in range(n_windows):
        mid = float(np.mean([f.window_stress_mid_pa[k] for f in report.packings]))
        report.comparisons.append(_compare(f"E' at {mid / 1000:.1f} kPa (window {k + 1})",
                                           [f.window_modulus_pa[k] for f in dem], [f.window_modulus_pa[k] for f in lig],
                                           MODULUS_TOLERANCE))
        report.comparisons[-1].gating = False
    return report
