#!/usr/bin/env python3
"""demcal vs LIGGGHTS on the same workload: throughput at 1 and 2 threads/ranks, peak memory, bulk density.

Workload (issue 2; the peers' LIGGGHTS input, copied to bench/liggghts/):
5,000 spheres, radii 10 / 12.5 / 15 mm in equal numbers, density 2,500 kg/m3, contact
kn = kt = 1.72 MN/m, friction 0.86 (particle-particle and particle-wall), normal dashpot at
0.8 of critical (tangential dashpot off), poured at rest from a random non-overlapping
insertion in r < 0.279 m, 0.005 < z < 0.79 m into a 0.59 m diameter cylinder with a floor,
settled, then compressed by a flat lid: approach 18 mm at 0.2 m/s, load 20 mm, unload
2 mm, reload 4 mm at 0.05 m/s. Both engines run at dt = 0.2 sqrt(m_min / kn).

Stiffness: demcal is PFC-style (entity stiffnesses in series), so kp = 3.44 MN/m gives a
particle-particle contact of 1.72 MN/m; walls get kw = kp (not "very stiff"): a wall
contact is kp kw / (kp + kw), which only equals 1.72 MN/m for kw = kp.

Prerequisite for the LIGGGHTS half (not installed at import time):
    apt-get install -y liggghts          (or run this script with --install)
Without LIGGGHTS the demcal figures are still measured and printed.

Throughput = particles x steps / wall seconds of the stepping loop, set-up and compilation
excluded (LIGGGHTS: its 'Loop time'; demcal: a warm-up step compiles first). Each demcal
thread count runs in its own process (NUMBA_NUM_THREADS), so peak RSS is per run.
Bulk density = total mass / (pi R^2 h_surf), h_surf = mean over 5 cm cells within r < 0.25 m
of the highest sphere top (peers/analyze_packing.py), after the settle phase.

The engines run in --rounds alternating rounds (default 2: demcal first, then LIGGGHTS first) and the
fastest run of each is compared, so a drift in the machine's speed between runs cannot favour either.

Usage: python3 bench/engine_vs_liggghts.py [--quick] [--install] [--threads 1 2] [--no-liggghts] [--rounds 2]
The last line is machine readable: ratio_1thread=X ratio_2thread=Y bulk_density_diff_pct=Z
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import subprocess
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(HERE, "liggghts"))
if ROOT not in sys.path:
    sys.path.insert(0, ROOT)

import runner as lig  # noqa: E402  (bench/liggghts/runner.py)

N_PARTICLES = 5000
RADII_M = (0.0100, 0.0125, 0.0150)
DENSITY = 2500.0
KN_CONTACT = 1.72e6
FRICTION = 0.86
ZETA = 0.8
DTFAC = 0.2
CYL_R = 0.295
INSERT_R, INSERT_Z = 0.279, (0.005, 0.79)
FULL = dict(TPOUR=0.5, TSETL=0.5, DAPP=0.018, VAPP=0.2, DLOAD=0.020, DUNL=0.002, DREL=0.004, VLID=0.05)
QUICK = dict(TPOUR=0.12, TSETL=0.04, DAPP=0.004, VAPP=0.2, DLOAD=0.002, DUNL=0.0005, DREL=0.0005, VLID=0.05)
PHASES = ("pour", "settle", "approach", "load", "unload", "reload")
DENSE = ("settle", "approach", "load", "unload", "reload")


def timestep_s() -> float:
    m_min = DENSITY * 4.0 / 3.0 * math.pi * RADII_M[0] ** 3
    return DTFAC * math.sqrt(m_min / KN_CONTACT)


def phase_steps(w: dict) -> dict[str, int]:
    """Same rounding as the LIGGGHTS input: round(time / dt)."""
    dt = timestep_s()
    return dict(pour=round(w["TPOUR"] / dt), settle=round(w["TSETL"] / dt), approach=round(w["DAPP"] / w["VAPP"] / dt),
                load=round(w["DLOAD"] / w["VLID"] / dt), unload=round(w["DUNL"] / w["VLID"] / dt),
                reload=round(w["DREL"] / w["VLID"] / dt))


# ----------------------------------------------------------------------------- demcal worker


def demcal_worker(threads: int, workload: dict, seed: int) -> dict:
    """One demcal run in this process (NUMBA_NUM_THREADS set by the parent)."""
    from engine.config import CylinderGeom, MaterialSpec, MeshGeom, PlaneGeom, SimulationConfig, WallSpec
    from engine.io.stl import plate
    from engine.particles.generation import CylinderRegion, insert_random
    from engine.particles.templates import sphere
    from engine.simulation import Simulation

    kp = 2.0 * KN_CONTACT  # series: kp kp / (kp + kp) = kn
    kw = kp  # series: kp kw / (kp + kw) = kn for particle-wall too
    cfg = SimulationConfig(
        materials=[MaterialSpec(density_kg_m3=DENSITY, normal_stiffness_n_per_m=kp, shear_to_normal_stiffness_ratio=1.0,
                                friction=FRICTION, damping_ratio_normal=ZETA, damping_ratio_shear=0.0)],
        timestep_s=timestep_s(), skin_m=0.005, threads=threads, record_every=100)
    sim = Simulation(cfg)
    counts = np.array([N_PARTICLES // 3 + (1 if k < N_PARTICLES % 3 else 0) for k in range(3)])
    idx = np.random.default_rng(seed).permutation(np.repeat(np.arange(3), counts))
    packing = insert_random([sphere(r) for r in RADII_M], idx, CylinderRegion(INSERT_R, *INSERT_Z), seed=seed)
    sim.add_packing(packing)
    wall = dict(normal_stiffness_n_per_m=kw, friction=FRICTION)
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(point_m=(0, 0, 0), normal=(0, 0, 1)), **wall))
    sim.add_wall(WallSpec(name="cylinder", geometry=CylinderGeom(base_m=(0, 0, -0.01), radius_m=CYL_R, height_m=1.2),
                          **wall))
    steps = phase_steps(workload)
    sim.run(steps=1)  # compiles (or loads the cached kernel) and builds the first neighbour list
    out = dict(threads=threads, dt_s=sim.timestep_s, critical_dt_s=sim.timestep_report().critical_s,
               n=sim.n_bodies, phases={})

    def timed(name):
        t0, c0 = time.perf_counter(), time.process_time()
        done = sim.run(steps=steps[name])
        out["phases"][name] = dict(steps=done, loop_s=time.perf_counter() - t0, cpu_s=time.process_time() - c0,
                                   atoms=sim.n_bodies)

    timed("pour")
    timed("settle")
    pos, rad, mass = sim.sphere_positions_m(), sim.sphere_radii_m(), sim.body_masses_kg()
    out["packing"] = lig.bulk_density_kg_m3(pos, rad, mass)
    out["kinetic_energy_j"] = sim.kinetic_energy()
    z_lid = float(pos[:, 2].max() + RADII_M[2] + 0.001)  # as the LIGGGHTS input: highest centre + r_max + 1 mm
    sim.add_wall(WallSpec(name="lid", geometry=MeshGeom(triangles_m=plate(0.35, z_lid)), **wall))
    for name, v in (("approach", -workload["VAPP"]), ("load", -workload["VLID"]), ("unload", workload["VLID"]),
                    ("reload", -workload["VLID"])):
        sim.set_wall_velocity("lid", (0.0, 0.0, v))
        timed(name)
    out["lid_force_end_n"] = float(sim.wall_force("lid")[2])
    out["max_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


def run_demcal(threads: int, workload: dict, seed: int) -> dict:
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads), OMP_NUM_THREADS="1")
    with tempfile.NamedTemporaryFile("r", suffix=".json") as fh:
        cmd = [sys.executable, os.path.abspath(__file__), "--worker", str(threads), "--json", fh.name,
               "--seed", str(seed)] + (["--quick"] if workload is QUICK else [])
        subprocess.run(cmd, env=env, check=True, cwd=ROOT)
        return json.load(open(fh.name))


# ----------------------------------------------------------------------------- report


def throughput(phases: dict, names=PHASES) -> float:
    steps = sum(phases[p]["steps"] * phases[p]["atoms"] for p in names if p in phases)
    secs = sum(phases[p]["loop_s"] for p in names if p in phases)
    return steps / secs if secs > 0 else float("nan")


def print_table(label: str, res: dict) -> None:
    ph = res["phases"]
    print(f"\n{label}: dt = {res.get('dt_s', float('nan')):.4e} s, peak RSS {res['max_rss_mb']:.0f} MB")
    print(f"  {'phase':9s} {'steps':>7s} {'wall s':>8s} {'particle-steps/s':>17s}")
    for p in PHASES:
        if p in ph:
            r = ph[p]
            print(f"  {p:9s} {r['steps']:7d} {r['loop_s']:8.2f} {r['steps'] * r['atoms'] / max(r['loop_s'], 1e-12):17.3e}")
    print(f"  {'all':9s} {'':7s} {sum(ph[p]['loop_s'] for p in ph):8.2f} {throughput(ph):17.3e}"
          f"   dense phases: {throughput(ph, DENSE):.3e}")
    work = sum(ph[p]["steps"] * ph[p]["atoms"] for p in ph)
    cpu = res.get("cpu_s", sum(ph[p].get("cpu_s", float("nan")) for p in ph))
    print(f"  CPU time {cpu:.1f} s -> {work / cpu:.3e} particle-steps per CPU-second"
          + (" (whole run incl. set-up)" if "cpu_s" in res else " (stepping only)"))
    pk = res["packing"]
    print(f"  settled: h_surf = {pk['h_surf_m']:.4f} m, bulk density = {pk['bulk_density_kg_m3']:.1f} kg/m3 "
          f"({pk['n_inside']} particles, {pk['mass_kg']:.2f} kg)")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="short phases (smoke run; packing not settled)")
    ap.add_argument("--install", action="store_true", help="apt-get install -y liggghts if it is missing")
    ap.add_argument("--no-liggghts", action="store_true", help="measure demcal only")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--seed", type=int, default=20260)
    ap.add_argument("--rounds", type=int, default=2, help="alternating rounds per engine; the fastest is kept")
    ap.add_argument("--outdir", default=None, help="keep LIGGGHTS work folders here (default: a temp folder)")
    ap.add_argument("--worker", type=int, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--json", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    workload = QUICK if args.quick else FULL

    if args.worker is not None:
        res = demcal_worker(args.worker, workload, args.seed)
        with open(args.json, "w") as fh:
            json.dump(res, fh)
        return 0

    steps = phase_steps(workload)
    print(f"workload: {N_PARTICLES} spheres r = {RADII_M} m (equal numbers), rho = {DENSITY}, contact kn = kt = "
          f"{KN_CONTACT:.3g} N/m (demcal kp = kw = {2 * KN_CONTACT:.3g} N/m in series), mu = {FRICTION}, "
          f"zeta_n = {ZETA} (no tangential dashpot), dt = {timestep_s():.4e} s")
    print("steps per phase: " + ", ".join(f"{k} {v}" for k, v in steps.items()) + (" (QUICK)" if args.quick else ""))
    sys.stdout.flush()

    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores (a loaded machine slows both engines)")
    exe = None if args.no_liggghts else lig.liggghts_available()
    if exe is None and args.install and not args.no_liggghts:
        lig.install_liggghts()
        exe = lig.liggghts_available()
    if args.no_liggghts:
        print("\nLIGGGHTS skipped (--no-liggghts)")
    elif exe is None:
        print("\nLIGGGHTS not found: install it with `apt-get install -y liggghts` (or pass --install); "
              "demcal figures below stand alone")
    outdir = args.outdir or tempfile.mkdtemp(prefix="demcal_bench_")

    def run_liggghts(n: int) -> dict:
        r = lig.run_liggghts(n, outdir, dict(workload))
        return dict(phases=r["log"]["phases"], dt_s=r["log"].get("dt_s", float("nan")), max_rss_mb=r["max_rss_mb"],
                    packing=lig.bulk_density_kg_m3(r["xyz_m"], r["radius_m"], r["mass_kg"]), cpu_s=r["cpu_s"])

    # Rounds in alternating order (demcal then LIGGGHTS, then LIGGGHTS then demcal, ...), the fastest
    # run of each kept: this machine's speed drifts by tens of percent over minutes (a shared host), so
    # one run of each, minutes apart, can compare a fast spell with a slow one.
    demcal, liggghts = {}, {}
    engines = [("demcal", demcal, lambda n: run_demcal(n, workload, args.seed), "thread(s)")]
    if exe is not None:
        engines.append(("LIGGGHTS", liggghts, run_liggghts, "MPI rank(s)"))
    # alternating rounds guard a comparison; demcal alone needs one run per thread count
    rounds = args.rounds if exe is not None else 1
    for rnd in range(rounds):
        for n in args.threads:
            for label, best, run, unit in (engines if rnd % 2 == 0 else engines[::-1]):
                res = run(n)
                print_table(f"{label}, {n} {unit}, round {rnd + 1}", res)
                sys.stdout.flush()
                if n not in best or throughput(res["phases"]) > throughput(best[n]["phases"]):
                    best[n] = res

    print(f"\nsummary (particle-steps/s over all phases, fastest of {rounds} round(s) each; "
          "ratio = demcal / LIGGGHTS, target >= 1.25):")
    ratios = {}
    for n in args.threads:
        d = throughput(demcal[n]["phases"])
        line = f"  {n} thread(s)/rank(s): demcal {d:.3e} (peak RSS {demcal[n]['max_rss_mb']:.0f} MB)"
        if n in liggghts:
            g = throughput(liggghts[n]["phases"])
            ratios[n] = d / g
            line += f", LIGGGHTS {g:.3e} (peak RSS {liggghts[n]['max_rss_mb']:.0f} MB), ratio {ratios[n]:.2f} (dense phases: " \
                    f"{throughput(demcal[n]['phases'], DENSE) / throughput(liggghts[n]['phases'], DENSE):.2f})"
        print(line)
    print(f"  load average after: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    diff = float("nan")
    ref = min(args.threads)
    if ref in liggghts:
        bd, bl = demcal[ref]["packing"]["bulk_density_kg_m3"], liggghts[ref]["packing"]["bulk_density_kg_m3"]
        diff = 100.0 * (bd - bl) / bl
        print(f"  bulk density after settling: demcal {bd:.1f} kg/m3, LIGGGHTS {bl:.1f} kg/m3, "
              f"difference {diff:+.2f} % (target within 2 %)" + (" -- QUICK run: not settled" if args.quick else ""))
    print(f"ratio_1thread={ratios.get(1, float('nan')):.3f} ratio_2thread={ratios.get(2, float('nan')):.3f} "
          f"bulk_density_diff_pct={diff:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
