#!/usr/bin/env python3
"""Time the kernel's pieces on the settled dense 5,000-sphere packing of bench/engine_throughput.py.

Where a step goes: the pair pass, the body pass (forces only, then with the kick, then with kick and
drift), the wall resultants, a neighbour rebuild, and whole steps (minimum over 20-step runs, and the
mean over a 2,000-step run). Each piece is the minimum of `--reps` calls, so two trees can be compared
on a busy machine by running this alternately in each (`python3 bench/kernel_pieces.py --checkpoint F`
from each checkout, same F): minima are far steadier than means under load.

    python3 bench/kernel_pieces.py [--checkpoint settled.npz] [--reps 100]

Run with NUMBA_NUM_THREADS=1 for the one-thread figures (two-thread minima mean little on a loaded
machine: a descheduled OpenMP thread stalls the region). The last line is machine readable.
"""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, ROOT)
sys.path.insert(0, HERE)


def _min_us(call, reps: int) -> float:
    best = float("inf")
    for _ in range(reps):
        t0 = time.perf_counter()
        call()
        best = min(best, time.perf_counter() - t0)
    return best * 1e6


def measure(checkpoint: str, reps: int) -> dict:
    from engine.simulation import Simulation

    sim = Simulation.from_checkpoint(checkpoint)
    sim.run(steps=300)  # compile or load the kernels, first neighbour list
    kern = sim.kernel
    pairs, spheres, bodies, walls, wall_contacts = sim.pairs, sim.spheres, sim.bodies, sim.walls, sim.wall_contacts
    dt = sim.timestep_s
    g = sim.config.gravity_m_s2
    moved = np.zeros((bodies.pos.shape[0] + kern.CHUNK - 1) // kern.CHUNK)

    def body_pass(finish: bool, go_on: bool):
        return lambda: kern.update_bodies(bodies, spheres, walls, pairs, wall_contacts, sim.props, sim.n_materials,
                                          dt, dt, g[0], g[1], g[2], False, finish, go_on, moved)

    out = {
        "pairs": int(pairs.j.shape[0]),
        "pair_pass_us": _min_us(lambda: kern.pair_forces(pairs, spheres, bodies, sim.props, sim.n_materials, dt,
                                                         False), reps),
        "body_forces_us": _min_us(body_pass(False, False), reps),
        "body_kick_us": _min_us(body_pass(True, False), reps),
        "body_kick_drift_us": _min_us(body_pass(True, True), reps),
        "wall_resultants_us": _min_us(lambda: kern.wall_resultants(
            walls.kind.shape[0], wall_contacts.wall, wall_contacts.force, wall_contacts.point, wall_contacts.k,
            walls.origin, walls.force, walls.moment, walls.k_sum), reps),
        "rebuild_us": _min_us(sim.rebuild_neighbours, max(3, reps // 5)),
    }
    # the body-pass calls above kicked and drifted the bodies without fresh forces: whole steps are
    # timed on the settled packing restored, not on that disturbed state
    sim = Simulation.from_checkpoint(checkpoint)
    sim.run(steps=300)
    out["step_us"] = _min_us(lambda: sim.run(steps=20), max(5, reps // 2)) / 20
    t0 = time.perf_counter()
    done = sim.run(steps=2000)
    out["particle_steps_per_s"] = sim.n_bodies * done / (time.perf_counter() - t0)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--checkpoint", default=None,
                    help="a settled packing saved by an earlier run (made and kept here when missing)")
    ap.add_argument("--reps", type=int, default=100)
    args = ap.parse_args(argv)
    import engine_throughput

    with tempfile.TemporaryDirectory() as tmp:
        path = args.checkpoint or os.path.join(tmp, "settled.npz")
        if not os.path.exists(path):
            engine_throughput.build_and_settle(path, 0.6)
        res = measure(path, args.reps)
    print(f"load average {os.getloadavg()[0]:.1f}, NUMBA_NUM_THREADS={os.environ.get('NUMBA_NUM_THREADS', 'all')}")
    print(f"pair pass {res['pair_pass_us']:.0f} us ({1e3 * res['pair_pass_us'] / res['pairs']:.1f} ns per candidate "
          f"pair, {res['pairs']} pairs); body pass {res['body_forces_us']:.0f} us forces only, "
          f"{res['body_kick_us']:.0f} with the kick, {res['body_kick_drift_us']:.0f} with kick and drift; "
          f"wall resultants {res['wall_resultants_us']:.0f} us; rebuild {res['rebuild_us']:.0f} us; "
          f"step {res['step_us']:.0f} us")
    print(" ".join(f"{k}={v:.4g}" for k, v in res.items()))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
