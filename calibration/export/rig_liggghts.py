"""The screening rig's fill and confined compression test, written for LIGGGHTS, and its runner.

Why its own module: the proof that an export holds (``calibration.export.verify``) must run the
exported include in the same rig demcal's lab uses (engine/lab/procedures/fill.py, cct.py, lid.py),
step for step where LIGGGHTS can: rainfall of a loose column (solid fraction 0.22, 1.15 x the
expected solid volume) in the container, settle to a kinetic-energy ratio KE/(M g d) < 1e-4,
delete the bodies whose centre is above the packing height, settle to 1e-5, lid 0.05 r_min above the
highest sphere top, then N cycles of loading at constant lid speed to the CCT stress and unloading to
zero force, sampled every 20 um of lid travel. Set-up differences that remain: LIGGGHTS' container is
one primitive cylinder (demcal's is two halves with a 1 mm gap closed by rings, aligned during the
CCT) and the lid is a square mesh plate covering the cylinder (demcal: a disc of the container's
radius), and a clump is deleted when any of its spheres has its centre above the level (LIGGGHTS' fix
multisphere removes a body with its first sphere; demcal deletes by the body's centre of mass). The
include itself is ``calibration.export.liggghts.render``'s text, unchanged.

``packing_cct_input`` / ``run_packing_cct`` run the same CCT from a packing built elsewhere (demcal's fill,
read with ``read_data``), so that both engines can be compared on one packing (``calibration.export.paired``):
single spheres as they are, clumps as ``fix rigid`` bodies (``RigidBodies``), since fix multisphere only
inserts its bodies from templates at random.
"""
from __future__ import annotations

import math
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass

import numpy as np

from calibration.export.liggghts import LiggghtsExport

REQUIRE_ENV = "DEMCAL_REQUIRE_LIGGGHTS"


def liggghts_executable() -> str | None:
    """Debian's ``liggghts`` (apt-get install liggghts: LIGGGHTS-PUBLIC 3.8.0)."""
    return shutil.which("liggghts")


@dataclass(frozen=True)
class Rig:
    """The screening rig (engine/lab/presets.py SCREENING) and the test's controls."""

    container_radius_m: float
    packing_height_m: float
    cct_max_stress_pa: float
    lid_speed_m_s: float
    cct_cycles: int
    expected_solid_fraction: float = 0.58
    fill_margin: float = 1.15
    column_solid_fraction: float = 0.22
    lid_travel_per_sample_m: float = 2e-5
    lid_start_gap_fraction: float = 0.05

    @property
    def area_m2(self) -> float:
        return float(np.pi * self.container_radius_m ** 2)


def screening_rig(cct_cycles: int, speed_factor: float | None = None) -> Rig:
    from engine.lab.procedures.fill import COLUMN_SOLID_FRACTION
    from engine.lab.procedures.lid import LID_START_GAP_FRACTION, LID_TRAVEL_PER_SAMPLE_M
    from engine.lab.presets import SCREENING as p

    factor = p.default_speed_factor if speed_factor is None else speed_factor
    return Rig(p.container_radius_m, p.packing_height_m, p.cct_max_stress_pa, p.lab_lid_speed_m_s * factor,
               cct_cycles, p.expected_solid_fraction, p.fill_margin, COLUMN_SOLID_FRACTION,
               LID_TRAVEL_PER_SAMPLE_M, LID_START_GAP_FRACTION)


@dataclass(frozen=True)
class ClumpBody:
    """The one clump of a clump material in the rig: LIGGGHTS' ``mass(all)`` is refused with fix multisphere,
    so the bulk mass is counted as atoms / spheres per body x the body's mass."""

    spheres_per_body: int
    mass_kg: float


def _energy_lines(mean_diameter_m: float, clump: ClumpBody | None) -> str:
    """The kinetic-energy ratio KE/(M g d) the settling loops read, as engine/lab/sim.py computes it."""
    if clump is None:
        return f"""compute rke all erotate/sphere
variable mass_total equal mass(all)
variable ke_ratio equal (ke+c_rke)/((v_mass_total+1e-30)*9.81*{mean_diameter_m:.8g})"""
    return f"""compute kems all ke/multisphere
compute rkems all erotate/multisphere
variable mass_total equal atoms/{clump.spheres_per_body}*{clump.mass_kg:.10g}
variable ke_ratio equal (c_kems+c_rkems)/((v_mass_total+1e-30)*9.81*{mean_diameter_m:.8g})"""


def _container_lines(r: float, integrator: str = "fix integ all nve/sphere") -> str:
    """Material, integration, gravity and the container (floor plane and one primitive cylinder)."""
    return f"""include      material.in
timestep     ${{demcal_dt}}
{integrator}
fix grav all gravity 9.81 vector 0.0 0.0 -1.0
fix floor all wall/gran ${{demcal_wall_model}} primitive type ${{demcal_wall_type}} zplane 0.0 ${{demcal_wall_settings}}
fix cyl all wall/gran ${{demcal_wall_model}} primitive type ${{demcal_wall_type}} zcylinder {r:.6g} 0.0 0.0 ${{demcal_wall_settings}}
"""


def _settle_lines(label: str, threshold: float, chunk_steps: int, min_chunks: int, max_chunks: int) -> str:
    """Run in chunks until KE/(M g d) < threshold (at least ``min_chunks``), as engine/lab/sim.settle."""
    cond = f"${{ke_ratio}} < {threshold:g}" if min_chunks <= 0 else \
        f"(${{{label}}} >= {min_chunks}) && (${{ke_ratio}} < {threshold:g})"
    return f"""variable {label} loop {max_chunks}
label {label}
run {chunk_steps}
if "{cond}" then "jump SELF {label}_done"
next {label}
jump SELF {label}
label {label}_done
"""


def _cct_lines(rig: Rig, r_min_m: float, dt_s: float) -> str:
    """From a settled, levelled packing (``c_ztop`` its highest sphere top): dump it, place the lid
    ``lid_start_gap_fraction`` r_min above the top, then the load-unload cycles (engine/lab/procedures/lid.py)."""
    chunk_lid = max(1, int(rig.lid_travel_per_sample_m / (rig.lid_speed_m_s * dt_s)))
    lines = f"""run 0
variable h equal c_ztop
variable h_fill equal ${{h}}
print "FILLED time=$(time) atoms=$(atoms) height=${{h_fill}} mass=${{mass_total}} ratio=${{ke_ratio}}"
write_dump all custom settled.txt id type radius mass x y z modify format "%d %d %.10g %.10g %.12g %.12g %.12g"
# confined compression: lid {rig.lid_start_gap_fraction} r_min above the highest sphere top
variable zlid0 equal ${{h_fill}}+{rig.lid_start_gap_fraction * r_min_m:.8g}
fix lid all mesh/surface/stress file lid.stl type ${{demcal_wall_type}} move 0.0 0.0 ${{zlid0}} reference_point 0.0 0.0 0.0
fix lidwall all wall/gran ${{demcal_wall_model}} mesh n_meshes 1 meshes lid ${{demcal_wall_settings}}
variable sig equal f_lid[3]/{rig.area_m2:.10g}
variable tl equal time
variable fzl equal f_lid[3]
variable zl equal f_lid[9]
thermo_style custom step time atoms ke v_sig
thermo {chunk_lid * 50}
fix prlid all print {chunk_lid} "${{tl}} ${{zl}} ${{fzl}}" file lid.txt screen no title "# time_s lid_z_m lid_fz_n"
"""
    max_chunks = int(0.3 * rig.packing_height_m / rig.lid_travel_per_sample_m) + 1
    for cycle in range(1, rig.cct_cycles + 1):
        lines += f"""print "CYCLE {cycle} load"
fix mv all move/mesh mesh lid linear 0.0 0.0 {-rig.lid_speed_m_s:.8g}
variable l{cycle} loop {max_chunks}
label load{cycle}
run {chunk_lid}
if "${{sig}} >= {rig.cct_max_stress_pa:.8g}" then "jump SELF load{cycle}_done"
next l{cycle}
jump SELF load{cycle}
label load{cycle}_done
unfix mv
print "CYCLE {cycle} unload"
fix mv all move/mesh mesh lid linear 0.0 0.0 {rig.lid_speed_m_s:.8g}
variable u{cycle} loop {max_chunks}
label unload{cycle}
run {chunk_lid}
if "${{sig}} <= 0.0" then "jump SELF unload{cycle}_done"
next u{cycle}
jump SELF unload{cycle}
label unload{cycle}_done
unfix mv
"""
    return lines + 'print "DONE"\n'


_TOP_LINES = """compute rad all property/atom radius
variable top atom z+c_rad
compute ztop all reduce max v_top
"""
MAX_SETTLE_CHUNKS = 250  # 5 s of 0.02 s chunks, as engine/lab/stops.py's rainfall limit


def rig_input(export: LiggghtsExport, rig: Rig, seed_prime: int, r_min_m: float, r_max_m: float,
              mean_diameter_m: float, clump: ClumpBody | None = None) -> str:
    """The LIGGGHTS main input: reads ``material.in`` (the export) and runs fill + CCT. A material with
    clumps runs with exactly one clump shape (``clump``) and no single spheres, as the screening rig's."""
    if export.has_clumps and clump is None:
        raise ValueError("a clump material needs its clump body (spheres per body, mass) in the rig")
    r = rig.container_radius_m
    solid = rig.fill_margin * rig.expected_solid_fraction * rig.area_m2 * rig.packing_height_m
    column_h = solid / (rig.column_solid_fraction * rig.area_m2)
    top = column_h + 4 * r_max_m + 0.05
    dt = export.timestep_s
    chunk_settle = max(1, round(0.02 / dt))
    return f"""# demcal screening rig (fill + confined compression) in LIGGGHTS; generated by calibration/export/rig_liggghts.py
atom_style   granular
atom_modify  map array
boundary     f f f
newton       off
communicate  single vel yes
units        si
region       box block {-r - 0.05:.6g} {r + 0.05:.6g} {-r - 0.05:.6g} {r + 0.05:.6g} -0.01 {top:.6g} units box
create_box   {export.n_atom_types} box
neighbor     {0.5 * r_min_m:.6g} bin
neigh_modify delay 0 every 1 check yes
{_container_lines(r)}region ins cylinder z 0.0 0.0 {r:.6g} 0.0 {column_h:.6g} units box
fix ins all insert/pack seed {seed_prime} distributiontemplate demcal_pdd maxattempt 1000 insert_every once &
    overlapcheck yes all_in yes vel constant 0. 0. 0. region ins volumefraction_region {rig.column_solid_fraction:.6g}
{_energy_lines(mean_diameter_m, clump)}
{_TOP_LINES}thermo_style custom step time atoms ke v_ke_ratio c_ztop
thermo       {chunk_settle * 10}
thermo_modify lost ignore norm no
run 1
unfix ins
print "INSERTED atoms=$(atoms)"
# settle to KE/(M g d) < 1e-4 (at least 0.2 s), as engine/lab/procedures/fill.py
{_settle_lines("s1", 1e-4, chunk_settle, 10, MAX_SETTLE_CHUNKS)}print "SETTLE1 time=$(time) ratio=${{ke_ratio}}"
region above block INF INF INF INF {rig.packing_height_m:.6g} INF units box
delete_atoms region above
{_settle_lines("s2", 1e-5, chunk_settle, 0, MAX_SETTLE_CHUNKS)}{_cct_lines(rig, r_min_m, dt)}"""


@dataclass(frozen=True)
class RigidBodies:
    """The clumps of a packing demcal built, for LIGGGHTS' ``fix rigid molecule``: each sphere's body (a
    molecule id) and each body's mass. Why not fix multisphere, which the include uses: LIGGGHTS-PUBLIC builds
    multisphere bodies only by inserting them from templates, at random places and orientations, so it cannot
    start from demcal's packing; fix rigid can, from ``read_data`` with a molecule id per sphere."""

    body_ids: np.ndarray  # per sphere, 0-based, the sphere order of the positions
    body_masses_kg: np.ndarray  # per body


def rigid_sphere_densities_kg_m3(radii_m: np.ndarray, bodies: RigidBodies) -> np.ndarray:
    """Per sphere, the density that makes each body's spheres weigh the body's mass. fix rigid takes a body's
    mass as the sum of its atoms' masses, which counts the overlap of a clump's spheres twice; demcal's (and the
    multisphere template's) body mass counts it once. Scaling the density keeps mass and weight exact; the
    inertia then counts the overlap's share twice too (a few per cent of a rotation's inertia, at quasi-static
    rates without effect on E')."""
    rad = np.asarray(radii_m, float)
    ids = np.asarray(bodies.body_ids, int)
    sphere_volume = 4.0 / 3.0 * np.pi * rad ** 3
    summed = np.bincount(ids, weights=sphere_volume, minlength=len(bodies.body_masses_kg))
    return np.asarray(bodies.body_masses_kg, float)[ids] / summed[ids]


def packing_data(positions_m: np.ndarray, radii_m: np.ndarray, density_kg_m3: float | np.ndarray, atom_type: int,
                 n_atom_types: int, box_m: tuple[float, float, float, float, float, float],
                 body_ids: np.ndarray | None = None) -> str:
    """A LIGGGHTS ``read_data`` file of a packing demcal built (``packing_cct_input``): single spheres in
    atom_style granular (id type diameter density x y z), or, with ``body_ids``, clumps' spheres in atom_style
    hybrid granular molecular (id type x y z diameter density molecule; molecule = body id + 1)."""
    pos = np.asarray(positions_m, float)
    rad = np.asarray(radii_m, float)
    if pos.ndim != 2 or pos.shape[1] != 3 or rad.shape != (pos.shape[0],):
        raise ValueError("positions must be (N, 3) and radii (N,)")
    rho = np.broadcast_to(np.asarray(density_kg_m3, float), rad.shape)
    lo_x, hi_x, lo_y, hi_y, lo_z, hi_z = box_m
    lines = ["LIGGGHTS data file: a packing built by demcal (calibration/export/rig_liggghts.py)", "",
             f"{pos.shape[0]} atoms", f"{n_atom_types} atom types", "",
             f"{lo_x:.8g} {hi_x:.8g} xlo xhi", f"{lo_y:.8g} {hi_y:.8g} ylo yhi", f"{lo_z:.8g} {hi_z:.8g} zlo zhi", "",
             "Atoms", ""]
    if body_ids is None:
        lines += [f"{k + 1} {atom_type} {2.0 * rad[k]:.12g} {rho[k]:.10g} {pos[k, 0]:.12g} {pos[k, 1]:.12g} "
                  f"{pos[k, 2]:.12g}" for k in range(pos.shape[0])]
    else:
        ids = np.asarray(body_ids, int)
        if ids.shape != rad.shape:
            raise ValueError("body_ids must give one body per sphere")
        lines += [f"{k + 1} {atom_type} {pos[k, 0]:.12g} {pos[k, 1]:.12g} {pos[k, 2]:.12g} {2.0 * rad[k]:.12g} "
                  f"{rho[k]:.10g} {ids[k] + 1}" for k in range(pos.shape[0])]
    return "\n".join(lines) + "\n"


def packing_box_m(rig: Rig, positions_m: np.ndarray, radii_m: np.ndarray) -> tuple[float, ...]:
    """The simulation box of ``rig_input`` around a given packing (room above it for the lid)."""
    r = rig.container_radius_m
    top = float(np.max(np.asarray(positions_m)[:, 2] + np.asarray(radii_m))) + 4 * float(np.max(radii_m)) + 0.05
    return (-r - 0.05, r + 0.05, -r - 0.05, r + 0.05, -0.01, top)


RIGID_INCLUDE_DROPS = ("fix demcal_ms all multisphere",)  # the include's lines fix rigid replaces


def rigid_include(export: LiggghtsExport) -> str:
    """The include for a packing of rigid clumps read from a data file: as exported, without ``fix
    multisphere`` (which refuses the molecular atom style fix rigid needs; its templates stay, unused)."""
    kept = [line for line in export.text.splitlines() if line.strip() not in RIGID_INCLUDE_DROPS]
    if len(kept) == len(export.text.splitlines()):
        raise ValueError("a clump include without 'fix demcal_ms all multisphere': not calibration.export.liggghts'")
    return "\n".join(kept) + "\n"


def packing_cct_input(export: LiggghtsExport, rig: Rig, r_min_m: float, mean_diameter_m: float,
                      settle_min_s: float = 0.05, rigid: bool = False) -> str:
    """The CCT alone, from a packing read from ``packing.data`` (``packing_data``): the spheres settle
    under the exported contact law until KE/(M g d) < 1e-5 (at least ``settle_min_s``: the contacts'
    tangential springs start unloaded, as demcal's would after a restart without history), then the lid
    and cycles exactly as ``rig_input``'s. Why: the two engines' confined moduli can then be compared on
    the same packing, and the scatter of packings (+-14-20 % of E' over three seeds) leaves the comparison.

    ``rigid``: the packing's clumps are rigid bodies (``RigidBodies``, molecule ids in the data file) moved by
    ``fix rigid molecule`` with the spheres of one body excluded from each other's neighbour lists, in place of
    fix multisphere (``rigid_include``). The pair style, its per-type-pair tables and the step are the include's;
    LIGGGHTS' pair gran takes a rigid body's mass as m* (checked in 3.8.0: a two-sphere body dropped on one of
    its spheres rebounds at the damping ratio the include's gamma gives for the body's mass, not the sphere's).
    The settle's kinetic energy is the atoms' (translation of each sphere: a body's rotation counted about the
    origin of its spheres, not its centre; a threshold, not a measurement)."""
    if export.has_clumps != rigid:
        raise ValueError("a clump material's packing needs rigid=True (its bodies), a sphere material's rigid=False")
    dt = export.timestep_s
    chunk_settle = max(1, round(0.02 / dt))
    min_chunks = max(1, math.ceil(settle_min_s / (chunk_settle * dt)))
    style = "hybrid granular molecular" if rigid else "granular"
    integrator = ("neigh_modify exclude molecule all\nfix integ all rigid molecule" if rigid
                  else "fix integ all nve/sphere")
    energy = f"""variable mass_total equal mass(all)
variable ke_ratio equal ke/((v_mass_total+1e-30)*9.81*{mean_diameter_m:.8g})""" if rigid else \
        _energy_lines(mean_diameter_m, None)
    return f"""# demcal CCT from a packing demcal built, in LIGGGHTS; generated by calibration/export/rig_liggghts.py
atom_style   {style}
atom_modify  map array
boundary     f f f
newton       off
communicate  single vel yes
units        si
read_data    packing.data
neighbor     {0.5 * r_min_m:.6g} bin
neigh_modify delay 0 every 1 check yes
{_container_lines(rig.container_radius_m, integrator)}{energy}
{_TOP_LINES}thermo_style custom step time atoms ke v_ke_ratio c_ztop
thermo       {chunk_settle * 10}
thermo_modify lost ignore norm no
{_settle_lines("s2", 1e-5, chunk_settle, min_chunks, MAX_SETTLE_CHUNKS)}{_cct_lines(rig, r_min_m, dt)}"""


@dataclass
class RigRun:
    packing_height_m: float
    bulk_mass_kg: float
    particle_count: int
    time_s: np.ndarray
    lid_z_m: np.ndarray
    lid_force_n: np.ndarray
    workdir: str
    wall_time_s: float

    def reduction(self, rig: Rig, height_m: float | None = None):
        """The CCT's reduction (engine.lab.reducers.cct) of the lid record: strain from the lid's first touch
        (the particles push the lid up: its force is +z on the mesh) over ``height_m`` (default the packing
        height LIGGGHTS printed)."""
        from engine.lab.reducers.cct import reduce_cct

        height = self.packing_height_m if height_m is None else float(height_m)
        stress = self.lid_force_n / rig.area_m2
        touching = np.nonzero(stress > 0)[0]
        z_contact = self.lid_z_m[touching[0]] if touching.size else self.lid_z_m[0]
        return reduce_cct((z_contact - self.lid_z_m) / height, stress, rig.area_m2, height)

    def settled_spheres(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The packing as LIGGGHTS had it before the lid (``settled.txt``): atom ids, radii and centres, by id."""
        rows = np.loadtxt(os.path.join(self.workdir, "settled.txt"), skiprows=9, ndmin=2)
        rows = rows[np.argsort(rows[:, 0])]
        return rows[:, 0].astype(int), rows[:, 2], rows[:, 4:7]


def run_rig(export: LiggghtsExport, rig: Rig, seed_prime: int, r_min_m: float, r_max_m: float,
            mean_diameter_m: float, workdir: str | None = None, timeout_s: float = 3600.0,
            clump: ClumpBody | None = None) -> RigRun:
    """Fill and CCT in LIGGGHTS (``rig_input``)."""
    text = rig_input(export, rig, seed_prime, r_min_m, r_max_m, mean_diameter_m, clump)
    return _run(export, rig, text, {}, workdir, timeout_s, 1 if clump is None else clump.spheres_per_body)


def run_packing_cct(export: LiggghtsExport, rig: Rig, positions_m: np.ndarray, radii_m: np.ndarray,
                    density_kg_m3: float, workdir: str | None = None, timeout_s: float = 3600.0,
                    bodies: RigidBodies | None = None) -> RigRun:
    """The CCT in LIGGGHTS from a packing built elsewhere (``packing_cct_input``): single spheres, or with
    ``bodies`` the clumps as rigid bodies."""
    radii = np.asarray(radii_m, float)
    box = packing_box_m(rig, positions_m, radii)
    if bodies is None:
        data = packing_data(positions_m, radii, density_kg_m3, export.particle_types[0], export.n_atom_types, box)
        mean_d = float(2.0 * np.mean(radii))  # single spheres: the lab's mean volume-equivalent diameter
        text = packing_cct_input(export, rig, float(np.min(radii)), mean_d)
        return _run(export, rig, text, {"packing.data": data}, workdir, timeout_s, 1)
    if len(export.particle_types) != 1:
        raise ValueError("the rigid packing takes a material of one clump type (the screening rig's)")
    data = packing_data(positions_m, radii, rigid_sphere_densities_kg_m3(radii, bodies), export.particle_types[0],
                        export.n_atom_types, box, body_ids=bodies.body_ids)
    # the lab's mean volume-equivalent diameter of the bodies
    masses = np.asarray(bodies.body_masses_kg, float)
    mean_d = float(np.mean(np.cbrt(6.0 * masses / (np.pi * density_kg_m3))))
    text = packing_cct_input(export, rig, float(np.min(radii)), mean_d, rigid=True)
    n_spheres = radii.size / masses.size
    return _run(export, rig, text, {"packing.data": data}, workdir, timeout_s, n_spheres,
                include=rigid_include(export))


def _run(export: LiggghtsExport, rig: Rig, main_text: str, files: dict[str, str], workdir: str | None,
         timeout_s: float, spheres_per_body: float, include: str | None = None) -> RigRun:
    import time

    from engine.io.stl import plate, write_stl

    exe = liggghts_executable()
    if exe is None:
        raise FileNotFoundError("liggghts not found (apt-get install -y liggghts)")
    work = tempfile.mkdtemp(prefix="demcal_lig_", dir=workdir)
    for name, text in {"material.in": export.text if include is None else include, "in.rig": main_text,
                       **files}.items():
        with open(os.path.join(work, name), "w") as fh:
            fh.write(text)
    write_stl(os.path.join(work, "lid.stl"), plate(rig.container_radius_m * 1.2))
    t0 = time.monotonic()
    with open(os.path.join(work, "screen.txt"), "w") as screen:
        proc = subprocess.run([exe, "-in", "in.rig", "-log", "log.lammps"], cwd=work, stdout=screen,
                              stderr=subprocess.STDOUT, timeout=timeout_s)
    wall = time.monotonic() - t0
    log = open(os.path.join(work, "log.lammps"), errors="replace").read()
    if proc.returncode != 0 or "DONE" not in log:
        tail = "\n".join(log.strip().splitlines()[-5:])
        raise RuntimeError(f"liggghts failed (exit {proc.returncode}) in {work}:\n{tail}")
    filled = [ln for ln in log.splitlines() if ln.startswith("FILLED ")][-1]
    fields = dict(kv.split("=") for kv in filled.split()[1:])
    data = np.loadtxt(os.path.join(work, "lid.txt"), ndmin=2)
    atoms = int(fields["atoms"])
    return RigRun(packing_height_m=float(fields["height"]), bulk_mass_kg=float(fields["mass"]),
                  particle_count=round(atoms / spheres_per_body), time_s=data[:, 0], lid_z_m=data[:, 1],
                  lid_force_n=data[:, 2], workdir=work, wall_time_s=wall)


def check_syntax(export: LiggghtsExport, steps: int = 10) -> str:
    """Run the include in LIGGGHTS for a few steps with a handful of particles on a floor; returns the
    log. Raises RuntimeError with LIGGGHTS' own error line when it refuses the include."""
    exe = liggghts_executable()
    if exe is None:
        raise FileNotFoundError("liggghts not found (apt-get install -y liggghts)")
    integrate = "fix integ all nve/sphere\n"
    main = f"""atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
units si
region box block -0.5 0.5 -0.5 0.5 -0.01 1.0 units box
create_box {export.n_atom_types} box
neighbor 0.002 bin
neigh_modify delay 0
include material.in
timestep ${{demcal_dt}}
{integrate}fix grav all gravity 9.81 vector 0.0 0.0 -1.0
fix floor all wall/gran ${{demcal_wall_model}} primitive type ${{demcal_wall_type}} zplane 0.0 ${{demcal_wall_settings}}
region ins block -0.3 0.3 -0.3 0.3 0.05 0.6 units box
fix ins all insert/pack seed 32452843 distributiontemplate {export.distribution_id} maxattempt 200 insert_every once &
    overlapcheck yes all_in yes vel constant 0. 0. -1. region ins particles_in_region 20
run {steps}
print "SYNTAX_OK"
"""
    with tempfile.TemporaryDirectory(prefix="demcal_ligsyn_") as work:
        with open(os.path.join(work, "material.in"), "w") as fh:
            fh.write(export.text)
        with open(os.path.join(work, "in.check"), "w") as fh:
            fh.write(main)
        proc = subprocess.run([exe, "-in", "in.check", "-log", "log.lammps"], cwd=work, capture_output=True,
                              text=True, timeout=600)
        log = open(os.path.join(work, "log.lammps"), errors="replace").read() if os.path.exists(
            os.path.join(work, "log.lammps")) else proc.stdout
    if proc.returncode != 0 or "SYNTAX_OK" not in log:
        errors = [ln for ln in (log + proc.stdout).splitlines() if "ERROR" in ln]
        raise RuntimeError("LIGGGHTS refused the include: " + (errors[0] if errors else log[-500:]))
    return log
