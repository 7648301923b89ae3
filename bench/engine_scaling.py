#!/usr/bin/env python3
"""Engine scaling: throughput and peak memory at about 5,000, 50,000 and 200,000 spheres, 1 and 2 threads.

Why: a calibration's cost must grow linearly with the particle count, the two-thread speed-up must
not fade on large packings, and the memory that grows with N must stay lean (issue 14).

Workload: the material of bench/engine_vs_liggghts.py (r = 10 / 12.5 / 15 mm in equal numbers,
rho = 2,500 kg/m3, contact kn = 1.72 MN/m, mu = 0.86, normal damping ratio 0.8, no tangential
dashpot, dt = 0.2 sqrt(m_min / kn), skin 5 mm). A unit of 5,000 spheres is poured from a loose grid
into a square box (0.52 m side, about the bench cylinder's cross-section) and settled once; larger
packings are copies of that unit in one box sized to hold them, face to face and mirrored in x for
odd columns and in y for odd rows, so that across every face between two copies each sphere that
touched the unit's side wall meets its own mirror image: every size is nearly the same dense, static
packing (density, contacts per particle) and only N changes. (Copies laid side by side unmirrored, a
gap or none, met the neighbour's unrelated face, lost the wall's lateral support and rearranged: 2.3-2.5
contacts per particle against the unit's 4.0 while measured; mirrored, the 50,000 packing keeps 3.3-3.8
over the first 2,000 steps, still relaxing slowly as a mirror contact is twice as stiff as the wall's.)

Each (size, threads) runs in a fresh process (peak RSS is per run, NUMBA_NUM_THREADS set before
numba starts). Throughput = particles x steps / wall seconds, best of the repeats, after a warm-up
that loads the cached kernel and builds the first neighbour lists. Bytes per particle = (peak RSS at
the largest size - peak RSS at the smallest) / (difference in particles), one thread: what grows with
N, without the fixed cost of Python, numpy and numba's compiled code.

    python3 bench/engine_scaling.py [--sizes 1 10 40] [--threads 1 2] [--repeats 2]

Last line (machine readable): throughput_ratio_200k_to_5k=X bytes_per_particle=Y
(X = 1-thread throughput at the largest size / at the smallest).
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

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

# the workload of engine_throughput.py (and engine_vs_liggghts.py): one definition of its material
from engine_throughput import FRICTION, KN as KN_CONTACT, RADII as RADII_M, RHO as DENSITY  # noqa: E402

UNIT_N = 5000
BOX_SIDE_M = 0.52  # square of about the 0.295 m cylinder's area
SETTLE_S = 0.6


def config(threads: int | None = None):
    from engine.config import MaterialSpec, SimulationConfig

    m_min = DENSITY * 4.0 / 3.0 * math.pi * RADII_M[0] ** 3
    return SimulationConfig(
        materials=[MaterialSpec(density_kg_m3=DENSITY, normal_stiffness_n_per_m=2 * KN_CONTACT, friction=FRICTION,
                                damping_ratio_normal=0.8, damping_ratio_shear=0.0)],
        timestep_s=0.2 * math.sqrt(m_min / KN_CONTACT), skin_m=0.005, threads=threads)


def add_box(sim, lx: float, ly: float) -> None:
    """Floor and four vertical plane walls around [0, lx] x [0, ly] (kw = kp: contact kn as particle pairs)."""
    from engine.config import PlaneGeom, WallSpec

    wall = dict(normal_stiffness_n_per_m=2 * KN_CONTACT, friction=FRICTION)
    for name, point, normal in (("floor", (0, 0, 0), (0, 0, 1)), ("x0", (0, 0, 0), (1, 0, 0)),
                                ("x1", (lx, 0, 0), (-1, 0, 0)), ("y0", (0, 0, 0), (0, 1, 0)),
                                ("y1", (0, ly, 0), (0, -1, 0))):
        sim.add_wall(WallSpec(name=name, geometry=PlaneGeom(point_m=point, normal=normal), **wall))


def settle_unit(path: str) -> None:
    """Pour UNIT_N spheres from a loose grid into the square box and let them settle; save positions and radii."""
    from engine.simulation import Simulation

    sim = Simulation(config())
    rng = np.random.default_rng(1)
    step = 2 * RADII_M[2] * 1.05
    grid = np.arange(step / 2, BOX_SIDE_M - step / 2, step)
    xy = np.array([(x, y) for x in grid for y in grid])
    layers = int(math.ceil(UNIT_N / len(xy)))
    pos = np.array([(x, y, step * (k + 0.5)) for k in range(layers) for x, y in xy])[:UNIT_N]
    pos[:, :2] += rng.uniform(-0.002, 0.002, (UNIT_N, 2))
    radii = rng.permutation(np.repeat(RADII_M, UNIT_N // 3 + 1))[:UNIT_N]
    sim.add_spheres(pos, radii)
    add_box(sim, BOX_SIDE_M, BOX_SIDE_M)
    t = time.perf_counter()
    sim.run(duration_s=SETTLE_S)
    print(f"unit of {UNIT_N} spheres settled for {SETTLE_S} s in {time.perf_counter() - t:.0f} s: kinetic energy "
          f"{sim.kinetic_energy():.2e} J, contacts (pp, pw) = {sim.contact_count()}", flush=True)
    np.savez(path, pos=sim.sphere_positions_m(), radius=sim.sphere_radii_m())


def tiles(copies: int) -> tuple[int, int]:
    """Most nearly square nx x ny arrangement of the unit copies."""
    nx = int(math.ceil(math.sqrt(copies)))
    while copies % nx:
        nx += 1
    return nx, copies // nx


def mirrored_copy(pos: np.ndarray, ix: int, iy: int) -> np.ndarray:
    """The unit's sphere centres for tile (ix, iy): mirrored in x on odd columns and in y on odd rows,
    so that neighbouring copies meet mirror image to mirror image, then moved into place."""
    out = pos.copy()
    if ix % 2:
        out[:, 0] = BOX_SIDE_M - out[:, 0]
    if iy % 2:
        out[:, 1] = BOX_SIDE_M - out[:, 1]
    return out + [ix * BOX_SIDE_M, iy * BOX_SIDE_M, 0.0]


def worker(unit_path: str, copies: int, steps: int, repeats: int) -> dict:
    from engine.simulation import Simulation

    unit = np.load(unit_path)
    nx, ny = tiles(copies)
    pos = np.concatenate([mirrored_copy(unit["pos"], ix, iy) for iy in range(ny) for ix in range(nx)])
    radius = np.tile(unit["radius"], copies)
    threads = int(os.environ.get("NUMBA_NUM_THREADS", "1"))
    sim = Simulation(config(threads))
    sim.add_spheres(pos, radius)
    add_box(sim, nx * BOX_SIDE_M, ny * BOX_SIDE_M)
    t = time.perf_counter()
    sim.run(steps=100)  # cached kernel, first lists, the copies settle against each other
    warm = time.perf_counter() - t
    best = math.inf
    for _ in range(repeats):
        t = time.perf_counter()
        sim.run(steps=steps)
        best = min(best, time.perf_counter() - t)
    n = sim.n_bodies
    pp, pw = sim.contact_count()
    return dict(n=n, threads=threads, steps=steps, best_s=best, warmup_s=warm, particle_steps_per_s=n * steps / best,
                contacts_per_particle=2.0 * pp / n, pairs=int(sim.pairs.i.size),
                max_rss_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[1, 10, 40], help="copies of the 5,000-sphere unit")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--work", type=float, default=2.0e7, help="particle-steps per timed repeat (min 500 steps)")
    ap.add_argument("--worker", nargs=2, default=None, help=argparse.SUPPRESS)
    ap.add_argument("--steps", type=int, default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(args.worker[0], int(args.worker[1]), args.steps, args.repeats)))
        return 0
    results: dict[tuple[int, int], dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        unit = os.path.join(tmp, "unit.npz")
        settle_unit(unit)
        print(f"load average: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores (timings are wall clock)")
        print(f"{'spheres':>8} {'threads':>7} {'steps':>6} {'particle-steps/s':>17} {'speed-up':>8} "
              f"{'contacts/particle':>17} {'peak RSS MB':>11}", flush=True)
        for copies in args.sizes:
            steps = max(500, int(args.work / (copies * UNIT_N)))
            for n_thr in args.threads:
                env = dict(os.environ, NUMBA_NUM_THREADS=str(n_thr), OMP_NUM_THREADS="1")
                out = subprocess.run([sys.executable, os.path.abspath(__file__), "--worker", unit, str(copies),
                                      "--steps", str(steps), "--repeats", str(args.repeats)],
                                     env=env, check=True, capture_output=True, text=True, cwd=ROOT)
                r = json.loads(out.stdout.strip().splitlines()[-1])
                results[(copies, n_thr)] = r
                one = results.get((copies, 1))
                speedup = r["particle_steps_per_s"] / one["particle_steps_per_s"] if one else float("nan")
                print(f"{r['n']:8d} {n_thr:7d} {steps:6d} {r['particle_steps_per_s']:17.3e} {speedup:8.2f} "
                      f"{r['contacts_per_particle']:17.2f} {r['max_rss_mb']:11.0f}", flush=True)
    lo, hi = min(args.sizes), max(args.sizes)
    t1 = min(args.threads)
    small, large = results[(lo, t1)], results[(hi, t1)]
    ratio = large["particle_steps_per_s"] / small["particle_steps_per_s"]
    per = (large["max_rss_mb"] - small["max_rss_mb"]) * 1024 * 1024 / max(large["n"] - small["n"], 1)
    print(f"fixed memory (runtime, numba, compiled kernels) ~ {small['max_rss_mb'] - per * small['n'] / 2**20:.0f} MB; "
          f"per particle {per:.0f} bytes")
    print(f"throughput_ratio_200k_to_5k={ratio:.3f} bytes_per_particle={per:.0f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
