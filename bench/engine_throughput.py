"""Engine throughput on a dense, settled packing of 5,000 spheres (particle-steps per second).

Workload as bench/engine_vs_liggghts.py: r = 10 / 12.5 / 15 mm, rho = 2500 kg/m3, contact kn = 1.72 MN/m
(kp = kw = 3.44 MN/m in series), mu = 0.86, normal damping ratio 0.8, no tangential dashpot,
dt = 0.2 sqrt(m_min / kn), skin 5 mm, in a 0.59 m cylinder. The packing starts on a loose grid, is
settled once (saved to a temporary checkpoint) and then timed at each thread count in a fresh process.

    python3 bench/engine_throughput.py [--threads 1 2] [--steps 3000]
"""
from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, ROOT)

KN = 1.72e6
RADII = (0.010, 0.0125, 0.015)
RHO = 2500.0
FRICTION = 0.86  # the LIGGGHTS input's coefficientFriction (particle-particle and wall)
N = 5000
CYL_R = 0.295


def build_and_settle(path: str, settle_s: float) -> None:
    from engine.config import CylinderGeom, MaterialSpec, PlaneGeom, SimulationConfig, WallSpec
    from engine.simulation import Simulation

    m_min = RHO * 4 / 3 * math.pi * RADII[0] ** 3
    cfg = SimulationConfig(
        materials=[MaterialSpec(density_kg_m3=RHO, normal_stiffness_n_per_m=2 * KN, friction=FRICTION,
                                damping_ratio_normal=0.8, damping_ratio_shear=0.0)],
        timestep_s=0.2 * math.sqrt(m_min / KN), skin_m=0.005)
    sim = Simulation(cfg)
    rng = np.random.default_rng(1)
    step = 2 * RADII[2] * 1.05
    grid = np.arange(-CYL_R + step, CYL_R - step / 2, step)
    xy = np.array([(x, y) for x in grid for y in grid if math.hypot(x, y) < CYL_R - step / 2])
    layers = int(math.ceil(N / len(xy)))
    pos = np.array([(x, y, step * (k + 0.5)) for k in range(layers) for x, y in xy])[:N]
    pos[:, :2] += rng.uniform(-0.002, 0.002, (N, 2))
    radii = rng.permutation(np.repeat(RADII, N // 3 + 1))[:N]
    sim.add_spheres(pos, radii)
    wall = dict(normal_stiffness_n_per_m=2 * KN, friction=FRICTION)
    sim.add_wall(WallSpec(name="floor", geometry=PlaneGeom(), **wall))
    sim.add_wall(WallSpec(name="cylinder", geometry=CylinderGeom(base_m=(0, 0, -0.01), radius_m=CYL_R,
                                                                   height_m=1.5), **wall))
    sim.run(duration_s=settle_s)
    print(f"settled {settle_s} s: kinetic energy {sim.kinetic_energy():.3e} J, "
          f"contacts (pp, pw) = {sim.contact_count()}", flush=True)
    sim.save(path)


def worker(path: str, steps: int) -> dict:
    from engine.simulation import Simulation

    sim = Simulation.from_checkpoint(path)
    sim.run(steps=200)  # compile / load the cached kernel, first neighbour list
    t0 = time.perf_counter()
    done = sim.run(steps=steps)
    wall_s = time.perf_counter() - t0
    return {"threads": int(os.environ.get("NUMBA_NUM_THREADS", "0")), "steps": done, "wall_s": wall_s,
            "particle_steps_per_s": sim.n_bodies * done / wall_s, "contacts": sim.contact_count()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--settle-s", type=float, default=0.6)
    ap.add_argument("--worker", default=None, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        print(json.dumps(worker(args.worker, args.steps)))
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "settled.npz")
        build_and_settle(path, args.settle_s)
        print(f"load average: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
        results = {}
        for n in args.threads:
            env = dict(os.environ, NUMBA_NUM_THREADS=str(n))
            out = subprocess.run([sys.executable, __file__, "--worker", path, "--steps", str(args.steps)],
                                 env=env, check=True, capture_output=True, text=True, cwd=ROOT)
            res = json.loads(out.stdout.strip().splitlines()[-1])
            results[n] = res
            print(f"{n} thread(s): {res['steps']} steps in {res['wall_s']:.2f} s -> "
                  f"{res['particle_steps_per_s']:.3e} particle-steps/s (contacts pp, pw = {res['contacts']})",
                  flush=True)
        print(" ".join(f"particle_steps_per_s_{n}thread={results[n]['particle_steps_per_s']:.4g}" for n in results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
