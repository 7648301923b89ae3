"""LIGGGHTS side of the engine-vs-LIGGGHTS benchmark: run the peer input, parse its log and dumps.

The input ``bench/liggghts/in.liggghts_settle_compress`` is the project's own peer
script (see its header). LIGGGHTS is a prerequisite, not a dependency:
``apt-get install -y liggghts`` (Debian package, LIGGGHTS-PUBLIC 3.8.0).
"""
from __future__ import annotations

import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
INPUT = os.path.join(HERE, "in.liggghts_settle_compress")
CONTAINER_RADIUS_M = 0.295

# wraps a command and reports the peak RSS of its largest process (ranks are waited-for descendants)
_RSS_WRAPPER = (
    "import resource, subprocess, sys, json\n"
    "rc = subprocess.run(sys.argv[1:]).returncode\n"
    "u = resource.getrusage(resource.RUSAGE_CHILDREN)\n"
    "print(json.dumps({'rc': rc, 'max_rss_kb': u.ru_maxrss, 'cpu_s': u.ru_utime + u.ru_stime}))\n"
)


def liggghts_available() -> str | None:
    return shutil.which("liggghts")


def install_liggghts() -> None:
    """Only with --install: the Debian package (needs root and network to the Debian mirror)."""
    cmd = ["apt-get", "install", "-y", "liggghts"]
    if subprocess.run(cmd).returncode != 0:
        subprocess.run(["apt-get", "update"], check=False)
        subprocess.run(cmd, check=True)


def parse_log(path: str) -> dict:
    """Per phase: steps, atoms and 'Loop time' seconds (setup excluded, as LIGGGHTS reports it)."""
    phases, name = {}, None
    settled = {}
    with open(path) as fh:
        for line in fh:
            m = re.match(r"^PHASE (\w+) steps=(\d+)", line)
            if m:
                name = m.group(1)
                continue
            m = re.match(r"^Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms", line)
            if m and name:
                phases[name] = dict(loop_s=float(m.group(1)), procs=int(m.group(2)), steps=int(m.group(3)),
                                    atoms=int(m.group(4)))
                name = None
            m = re.match(r"^SETTLED ztop_center=([0-9.eE+-]+) lid0=([0-9.eE+-]+)", line)
            if m:
                settled.update(ztop_center_m=float(m.group(1)), lid0_m=float(m.group(2)))
            m = re.match(r"^m1=([0-9.eE+-]+) m2=\S+ m3=\S+ dt=([0-9.eE+-]+)", line)
            if m:
                settled["dt_s"] = float(m.group(2))
    return dict(phases=phases, **settled)


def read_dump(path: str):
    """A 'write_dump custom ... id type radius mass x y z ...' file -> radius, mass, xyz."""
    d = np.loadtxt(path, skiprows=9, ndmin=2)
    return d[:, 2], d[:, 3], d[:, 4:7]


def run_liggghts(ranks: int, outdir: str, variables: dict[str, float | str]) -> dict:
    """Run the peer input with ``ranks`` MPI ranks; returns the parsed log, packing and peak memory."""
    exe = liggghts_available()
    if exe is None:
        raise FileNotFoundError("liggghts not found")
    from engine.io.stl import plate, write_stl

    os.makedirs(outdir, exist_ok=True)
    work = tempfile.mkdtemp(prefix="lig_", dir=outdir)
    shutil.copy(INPUT, work)
    write_stl(os.path.join(work, "lid.stl"), plate(0.35))  # 2-triangle plate covering the 0.295 m cylinder
    cmd = [exe, "-in", os.path.basename(INPUT), "-var", "OUTDIR", ".", "-log", "log.lammps", "-var", "PX", str(ranks)]
    for k, v in variables.items():
        cmd += ["-var", k, str(v)]
    if ranks > 1:
        cmd = ["mpirun", "--allow-run-as-root", "--oversubscribe", "-np", str(ranks)] + cmd
    with open(os.path.join(work, "screen.txt"), "w") as screen:
        proc = subprocess.run([sys.executable, "-c", _RSS_WRAPPER] + cmd, cwd=work, stdout=subprocess.PIPE,
                              stderr=screen, text=True)
    lines = [ln for ln in proc.stdout.splitlines() if ln.startswith("{")]
    meta = json.loads(lines[-1]) if lines else {"rc": proc.returncode, "max_rss_kb": 0}
    if meta["rc"] != 0:
        raise RuntimeError(f"liggghts exited with {meta['rc']}; see {work}/log.lammps")
    log = parse_log(os.path.join(work, "log.lammps"))
    radius, mass, xyz = read_dump(os.path.join(work, "settled.txt"))
    return dict(log=log, radius_m=radius, mass_kg=mass, xyz_m=xyz, max_rss_mb=meta["max_rss_kb"] / 1024.0,
                cpu_s=meta.get("cpu_s", float("nan")), workdir=work)


def surface_height_m(xyz_m: np.ndarray, radius_m: np.ndarray, cell_m: float = 0.05, r_max_m: float = 0.25) -> float:
    """h_surf (peers/analyze_packing.py): mean over 5 cm cells whose centre lies within 0.25 m of the
    axis of the highest sphere top in the cell."""
    top = xyz_m[:, 2] + radius_m
    ij = np.floor(xyz_m[:, :2] / cell_m).astype(np.int64)
    best: dict[tuple[int, int], float] = {}
    for (i, j), t in zip(map(tuple, ij), top):
        if t > best.get((i, j), -np.inf):
            best[(i, j)] = t
    tops = [t for (i, j), t in best.items() if math.hypot((i + 0.5) * cell_m, (j + 0.5) * cell_m) < r_max_m]
    return float(np.mean(tops))


def bulk_density_kg_m3(xyz_m, radius_m, mass_kg, container_radius_m: float = CONTAINER_RADIUS_M) -> dict:
    """Bulk density M / (pi R^2 h_surf) of the spheres inside the container (ejected ones left out)."""
    xyz_m, radius_m, mass_kg = np.asarray(xyz_m), np.asarray(radius_m), np.asarray(mass_kg)
    inside = (np.hypot(xyz_m[:, 0], xyz_m[:, 1]) < container_radius_m + 1e-3) & (xyz_m[:, 2] > -0.01) & (xyz_m[:, 2] < 2.0)
    h = surface_height_m(xyz_m[inside], radius_m[inside])
    m = float(mass_kg[inside].sum())
    return dict(h_surf_m=h, mass_kg=m, n_inside=int(inside.sum()),
                bulk_density_kg_m3=m / (math.pi * container_radius_m**2 * h))
