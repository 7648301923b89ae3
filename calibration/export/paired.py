"""Both engines' confined compression on the same packing (issue 30, item 4: where the engines differ).

``verify_export`` compares the engines over independent packings, one per seed in each: with ~740
spheres in the screening rig the confined modulus of single packings spreads +-14-20 %, so three seeds
cannot tell a 10 % engine difference from the packings' scatter. Here demcal builds each packing (its
lab's fill), and both engines run the CCT on that same packing: LIGGGHTS from the spheres' positions and
radii (``rig_liggghts.run_packing_cct``: the exported include, a settle to KE/(M g d) < 1e-5 because its
contacts start without tangential history, then the same lid and cycles), demcal twice, from its fill's
checkpoint as the lab runs it and restarted as LIGGGHTS starts (``without_history``, settled again). The
like-for-like pair is LIGGGHTS against demcal restarted (a clump packing's bodies are read as fix rigid
bodies, ``rig_liggghts.RigidBodies``); demcal restarted against demcal as run measures
what a restart alone does to one packing's E', the CCT's own chaotic scatter (measured: sd 14 % for one
cycle, as large as the engines' difference per packing; docs/export.md), so only means over packings
compare engines.

``contact_changes`` switches a contact setting in both engines for the CCT only (the packing is built
with the material as it is), so a set-up or convention can be removed one at a time on the same packings:
``damping_ratio_shear`` 0 takes the tangential dashpot out, whose Coulomb cap the two codes apply
differently (demcal caps spring + dashpot at mu Fn and keeps the capped force as the spring's stretch;
LIGGGHTS caps the spring alone and adds the dashpot only while sticking); ``friction_pp`` changes the
inter-particle friction.
"""
from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from calibration.export.liggghts import render
from calibration.export.material import ExportMaterial
from calibration.export.rig_liggghts import RigidBodies, run_packing_cct, screening_rig
from calibration.export.verify import to_micro_parameters

# the contact settings demcal can change on a built packing (engine.simulation.Simulation.set_material),
# named as the material card names them, with the engine's own name
CCT_CHANGES = {"damping_ratio_shear": "damping_ratio_shear", "damping_ratio_normal": "damping_ratio_normal",
               "friction_pp": "friction"}


@dataclass
class PairedPacking:
    """One packing's CCT in demcal as the lab runs it (``kept``: the fill's contact history), in demcal
    restarted as LIGGGHTS starts (history dropped, settled again) and in LIGGGHTS."""

    seed: int
    particle_count: int
    height_demcal_m: float
    height_liggghts_m: float  # after LIGGGHTS' own settle of the same packing
    modulus_kept_pa: float
    modulus_restarted_pa: float
    modulus_liggghts_pa: float
    window_stress_mid_pa: list[float]
    window_modulus_kept_pa: list[float]
    window_modulus_restarted_pa: list[float]
    window_modulus_liggghts_pa: list[float]
    wall_time_s: float


@dataclass
class PairedDifference:
    """(other - base) / base per packing: mean, standard deviation and standard error of the mean, with the
    two sides' own means."""

    quantity: str
    base_mean: float
    other_mean: float
    mean: float
    sd: float
    se: float
    n: int

    @property
    def distinguishable(self) -> bool:
        """The mean difference lies more than twice its standard error from zero."""
        return self.n > 1 and abs(self.mean) > 2.0 * self.se


@dataclass
class PairedReport:
    material: str
    label: str
    contact_changes: dict
    seeds: list[int]
    cct_cycles: int
    packings: list[PairedPacking] = field(default_factory=list)
    differences: list[PairedDifference] = field(default_factory=list)

    def to_dict(self) -> dict:
        return asdict(self)

    def text(self) -> str:
        changes = ", ".join(f"{k} {v:g}" for k, v in self.contact_changes.items()) or "none"
        lines = [f"paired CCT ({self.label}): {self.material}; changed for the CCT in both engines: {changes}; "
                 f"seeds {self.seeds}, {self.cct_cycles} cycles; E' of demcal as the lab runs it (history kept), "
                 "demcal restarted as LIGGGHTS starts (history dropped, settled again), LIGGGHTS"]
        for p in self.packings:
            lines.append(f"  seed {p.seed}: N {p.particle_count}  H {p.height_demcal_m * 1000:.1f} / "
                         f"{p.height_liggghts_m * 1000:.1f} mm  E' kept {p.modulus_kept_pa / 1e6:.3f}  restarted "
                         f"{p.modulus_restarted_pa / 1e6:.3f}  LIGGGHTS {p.modulus_liggghts_pa / 1e6:.3f} MPa  "
                         f"[{p.wall_time_s:.0f} s]")
        if self.packings:
            moved = [1000 * (p.height_liggghts_m - p.height_demcal_m) for p in self.packings]
            lines.append(f"  packing height after LIGGGHTS' settle minus demcal's: mean {np.mean(moved):+.2f} mm, "
                         f"range {min(moved):+.2f} to {max(moved):+.2f} mm")
        for d in self.differences:
            lines.append(f"  {d.quantity:44s} {d.base_mean:11.5g} -> {d.other_mean:11.5g}  paired difference "
                         f"{d.mean * 100:+6.1f} % +- {d.se * 100:.1f} % (sd {d.sd * 100:.1f} %, n {d.n})"
                         f"{'  DIFFERS' if d.distinguishable else ''}")
        return "\n".join(lines)


def paired_difference(quantity: str, base: list[float], other: list[float]) -> PairedDifference:
    """Mean relative difference (other - base) / base over pairs, with its standard error (sd / sqrt(n))."""
    d_arr, l_arr = np.asarray(base, float), np.asarray(other, float)
    rel = (l_arr - d_arr) / d_arr
    n = rel.size
    sd = float(np.std(rel, ddof=1)) if n > 1 else 0.0
    return PairedDifference(quantity, float(np.mean(d_arr)), float(np.mean(l_arr)), float(np.mean(rel)), sd,
                            sd / math.sqrt(n) if n > 1 else math.inf, n)


def _with_changes(material: ExportMaterial, changes: dict) -> ExportMaterial:
    unknown = sorted(set(changes) - set(CCT_CHANGES))
    if unknown:
        raise ValueError(f"contact_changes {unknown} cannot be changed on a built packing; only {sorted(CCT_CHANGES)}")
    contact = material.contact.model_copy(update=dict(changes))
    return material.model_copy(update={"contact": type(material.contact).model_validate(contact.model_dump())})


def without_history(checkpoint: dict) -> dict:
    """The checkpoint with every contact's history zeroed (tangential springs unloaded) and every body at rest:
    the state LIGGGHTS starts from when it reads the packing's positions."""
    state = dict(checkpoint)
    for key in ("p_hist", "c_hist", "pending_pair_hist", "pending_wall_hist"):
        if key in state:
            state[key] = np.zeros_like(state[key])
    for key in ("b_vel", "b_omega", "s_vel"):
        if key in state:
            state[key] = np.zeros_like(state[key])
    return state


@dataclass
class _DemcalSide:
    positions_m: np.ndarray
    radii_m: np.ndarray
    bodies: RigidBodies | None  # clumps: each sphere's body and each body's mass
    packing_height_m: float
    kept: object  # the CCT's reduction with the fill's contact history, as the lab runs it
    restarted: object  # the CCT's reduction after the history is dropped and the packing settles again


def _demcal_fill_and_cct(params, seed: int, cct_cycles: int, speed_factor: float | None, changes: dict) -> _DemcalSide:
    """demcal's lab: the fill, then (with ``changes`` applied to the settled packing) the CCT twice: once as
    the lab runs it, once restarted as LIGGGHTS is (history dropped, bodies at rest, settled to KE/(M g d) <
    1e-5). The second is the like-for-like partner of LIGGGHTS' run; the difference of the two demcal runs is
    what a restart alone does to E' on the same packing, the comparison's own scatter."""
    from engine.lab import sim as labsim
    from engine.lab.context import RunContext
    from engine.lab.procedures.cct import run_cct
    from engine.lab.procedures.fill import FillOutcome
    from engine.lab.registry import Bench, plan
    from engine.lab.spec import JobSpec, TestOptions

    spec = JobSpec(test="cct", fidelity="screening", seed=seed, parameters=params,
                   options=TestOptions(cct_cycles=cct_cycles, speed_factor=speed_factor))
    ctx = RunContext.from_spec(spec)
    ctx.validate()
    bench = Bench(ctx)
    steps = dict((test.name, test) for test, _ in plan(spec))
    ctx.phase(0.0, 1.0)
    fill = steps["fill"].run(bench, 0.0, 1.0).outcome
    sim = labsim.restore(fill.checkpoint)
    positions, radii = sim.sphere_positions_m(), sim.sphere_radii_m()
    bodies = None
    if sim.n_bodies != sim.n_spheres:  # clumps: LIGGGHTS reads them as rigid bodies (rig_liggghts.RigidBodies)
        ids = np.asarray(sim.sphere_body_ids())
        _, dense = np.unique(ids, return_inverse=True)  # public ids, in body order, as 0..n_bodies-1
        bodies = RigidBodies(dense.astype(int), np.asarray(sim.body_masses_kg(), float))
    if changes:
        sim.set_material(0, **{CCT_CHANGES[k]: v for k, v in changes.items()})
    kept = run_cct(ctx, FillOutcome(sim.checkpoint(), fill.properties, fill.packing_height_m)).reduction
    again = labsim.restore(without_history(sim.checkpoint()))
    labsim.settle(ctx, again, "paired: settling the restarted packing", threshold=1e-5, min_time_s=0.05)
    restarted = run_cct(ctx, FillOutcome(again.checkpoint(), fill.properties, fill.packing_height_m)).reduction
    return _DemcalSide(positions, radii, bodies, float(fill.packing_height_m), kept, restarted)


def paired_cct(material: ExportMaterial | dict, seeds=(1, 2, 3), cct_cycles: int = 2,
               speed_factor: float | None = None, contact_changes: dict | None = None, label: str = "",
               workdir: str | None = None, progress=None) -> PairedReport:
    """demcal builds one packing per seed; both engines run the CCT on it (see the module doc)."""
    if not isinstance(material, ExportMaterial):
        material = ExportMaterial.model_validate(material)
    changes = dict(contact_changes or {})
    params = to_micro_parameters(material)
    export = render(_with_changes(material, changes))
    rig = screening_rig(cct_cycles, speed_factor)
    report = PairedReport(material.name, label or ("as exported" if not changes else "changed"), changes,
                          list(seeds), cct_cycles)
    for seed in seeds:
        t0 = time.monotonic()
        if progress:
            progress(f"seed {seed}: demcal fill and CCT (history kept, then restarted)")
        dem = _demcal_fill_and_cct(params, seed, cct_cycles, speed_factor, changes)
        if progress:
            what = f"{dem.radii_m.size} spheres" if dem.bodies is None else \
                f"{dem.bodies.body_masses_kg.size} clumps (fix rigid)"
            progress(f"seed {seed}: LIGGGHTS CCT on the same {what}")
        run = run_packing_cct(export, rig, dem.positions_m, dem.radii_m, material.particles.solid_density_kg_m3,
                              workdir, bodies=dem.bodies)
        # strains over demcal's height, as demcal's own two runs: a height change in LIGGGHTS' settle (printed)
        # does not enter the moduli
        lig = run.reduction(rig, dem.packing_height_m)
        reds = (dem.kept, dem.restarted, lig)
        n_win = min(len(r.window_modulus_pa) for r in reds)
        packing = PairedPacking(
            seed, int(dem.radii_m.size if dem.bodies is None else dem.bodies.body_masses_kg.size),
            dem.packing_height_m, float(run.packing_height_m),
            float(dem.kept.confined_modulus_pa), float(dem.restarted.confined_modulus_pa),
            float(lig.confined_modulus_pa),
            [float(np.mean([r.window_stress_mid_pa[k] for r in reds])) for k in range(n_win)],
            *[list(map(float, r.window_modulus_pa[:n_win])) for r in reds], time.monotonic() - t0)
        report.packings.append(packing)
        if progress:
            progress(f"seed {seed}: E' kept {packing.modulus_kept_pa / 1e6:.3f}, restarted "
                     f"{packing.modulus_restarted_pa / 1e6:.3f}, LIGGGHTS {packing.modulus_liggghts_pa / 1e6:.3f} MPa")
    ps = report.packings
    pairs = (("LIGGGHTS vs demcal restarted", "restarted", "liggghts"),
             ("demcal restarted vs kept", "kept", "restarted"),
             ("LIGGGHTS vs demcal kept", "kept", "liggghts"))
    for name, base, other in pairs:
        report.differences.append(paired_difference(f"E' (cycles 2..N), {name}",
                                                    [getattr(p, f"modulus_{base}_pa") for p in ps],
                                                    [getattr(p, f"modulus_{other}_pa") for p in ps]))
    n_win = min(len(p.window_modulus_kept_pa) for p in ps)
    for k in range(n_win):
        mid = float(np.mean([p.window_stress_mid_pa[k] for p in ps]))
        report.differences.append(paired_difference(f"E' at {mid / 1000:.1f} kPa, LIGGGHTS vs restarted",
                                                    [p.window_modulus_restarted_pa[k] for p in ps],
                                                    [p.window_modulus_liggghts_pa[k] for p in ps]))
    return report


def clumps_of_liggghts_packing(run, template, body_mass_kg: float) -> tuple[RigidBodies, np.ndarray, np.ndarray]:
    """The bodies of a LIGGGHTS multisphere packing (``RigRun.settled_spheres``), as (bodies, radii, centres) in
    body order. Found by geometry, not atom ids (the fill's deletion above the level leaves the ids with gaps
    that do not follow the bodies): a clump's spheres overlap each other by far more than spheres of two bodies
    in a settled packing do (theirs stay below 1e-3 of a radius), so two spheres closer than 0.9 (r_i + r_j)
    belong to one body, and a body is a connected group of such pairs. Each group is checked against the
    template (its sphere count and its distances, sorted, to 1e-4 of the smallest radius; the dump holds 12
    digits), so a packing that is not the template's would be refused, not guessed."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    _, radii, centres = run.settled_spheres()
    n = int(template.n_spheres)
    r_max = float(np.max(radii))
    tree = cKDTree(centres)
    pairs = tree.query_pairs(2.0 * 0.9 * r_max, output_type="ndarray")
    if pairs.size:
        gap = np.linalg.norm(centres[pairs[:, 0]] - centres[pairs[:, 1]], axis=1)
        pairs = pairs[gap < 0.9 * (radii[pairs[:, 0]] + radii[pairs[:, 1]])]
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(radii.size, radii.size)) \
        if pairs.size else coo_matrix((radii.size, radii.size))
    count, labels = connected_components(graph, directed=False)
    sizes = np.bincount(labels, minlength=count)
    if np.any(sizes != n):
        raise ValueError(f"spheres group into bodies of {sorted(set(sizes.tolist()))} spheres, not the template's {n}")
    order = np.argsort(labels, kind="stable")
    groups = centres[order].reshape(count, n, 3)
    offsets = np.asarray(template.sphere_offsets_m, float)
    iu = np.triu_indices(n, 1)
    expected = np.sort(np.linalg.norm(offsets[:, None, :] - offsets[None, :, :], axis=2)[iu])
    found = np.sort(np.linalg.norm(groups[:, :, None, :] - groups[:, None, :, :], axis=3)[:, iu[0], iu[1]], axis=1)
    if np.max(np.abs(found - expected[None]), initial=0.0) > 1e-4 * float(np.min(template.sphere_radii_m)):
        raise ValueError("a group of overlapping spheres is not the template's body (its sphere distances differ)")
    bodies = RigidBodies(np.repeat(np.arange(count), n), np.full(count, body_mass_kg))
    return bodies, radii[order], centres[order]


@dataclass
class RestartPacking:
    """One LIGGGHTS packing's CCT as LIGGGHTS runs it (fix multisphere, the fill's history) and restarted from
    its settled spheres as rigid bodies (fix rigid, history dropped), as the paired CCT starts from demcal's."""

    seed: int
    bodies: int
    height_m: float
    modulus_multisphere_pa: float
    modulus_rigid_restarted_pa: float
    window_stress_mid_pa: list[float]
    window_modulus_multisphere_pa: list[float]
    window_modulus_rigid_restarted_pa: list[float]
    wall_time_s: float


def liggghts_restart_cct(material: ExportMaterial | dict, seeds=(1, 2, 3), cct_cycles: int = 2,
                         speed_factor: float | None = None, workdir: str | None = None,
                         progress=None) -> tuple[list[RestartPacking], list[PairedDifference]]:
    """LIGGGHTS' own clump packings (verify_export's, same seeds) run twice: as filled (fix multisphere) and
    restarted as rigid bodies (fix rigid). With ``paired_cct`` on demcal's packings this splits the engines'
    E' difference of clumps into the packing each fill builds, the integrator of the bodies and the restart:
    paired_cct compares the engines' contact mechanics on one packing; this compares LIGGGHTS' two rigid-body
    integrators (with the restart) on one packing."""
    from calibration.export.verify import liggghts_rig_run

    if not isinstance(material, ExportMaterial):
        material = ExportMaterial.model_validate(material)
    if not material.particles.clumps or material.particles.spheres or len(material.particles.clumps) != 1:
        raise ValueError("liggghts_restart_cct takes a material of one clump shape (fix multisphere's packing)")
    params = to_micro_parameters(material)
    export = render(material)
    rig = screening_rig(cct_cycles, speed_factor)
    template = material.particles.clumps[0].template()
    rho = material.particles.solid_density_kg_m3
    body_mass = template.mass_kg(rho)
    out: list[RestartPacking] = []
    for seed in seeds:
        t0 = time.monotonic()
        if progress:
            progress(f"seed {seed}: LIGGGHTS fill and CCT (fix multisphere)")
        run = liggghts_rig_run(export, rig, params, material, seed, workdir)
        bodies, radii, centres = clumps_of_liggghts_packing(run, template, body_mass)
        if progress:
            progress(f"seed {seed}: LIGGGHTS CCT restarted on its {bodies.body_masses_kg.size} clumps (fix rigid)")
        again = run_packing_cct(export, rig, centres, radii, rho, workdir, bodies=bodies)
        ms, rigid = run.reduction(rig), again.reduction(rig, run.packing_height_m)
        n_win = min(len(ms.window_modulus_pa), len(rigid.window_modulus_pa))
        out.append(RestartPacking(seed, int(bodies.body_masses_kg.size), float(run.packing_height_m),
                                  float(ms.confined_modulus_pa), float(rigid.confined_modulus_pa),
                                  [float(0.5 * (ms.window_stress_mid_pa[k] + rigid.window_stress_mid_pa[k]))
                                   for k in range(n_win)],
                                  list(map(float, ms.window_modulus_pa[:n_win])),
                                  list(map(float, rigid.window_modulus_pa[:n_win])), time.monotonic() - t0))
        if progress:
            progress(f"seed {seed}: E' multisphere {out[-1].modulus_multisphere_pa / 1e6:.3f}, rigid restarted "
                     f"{out[-1].modulus_rigid_restarted_pa / 1e6:.3f} MPa")
    diffs = [paired_difference("E' (cycles 2..N), LIGGGHTS rigid restarted vs multisphere",
                               [p.modulus_multisphere_pa for p in out], [p.modulus_rigid_restarted_pa for p in out])]
    n_win = min(len(p.window_modulus_multisphere_pa) for p in out)
    for k in range(n_win):
        mid = float(np.mean([p.window_stress_mid_pa[k] for p in out]))
        diffs.append(paired_difference(f"E' at {mid / 1000:.1f} kPa, rigid restarted vs multisphere",
                                       [p.window_modulus_multisphere_pa[k] for p in out],
                                       [p.window_modulus_rigid_restarted_pa[k] for p in out]))
    return out, diffs
