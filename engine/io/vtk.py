"""VTK XML PolyData (.vtp) output that ParaView opens, written with numpy only.

Particles are points (one per sphere) with ``radius``, ``velocity`` and
``body_id`` arrays: in ParaView, a Glyph filter (sphere, scale by ``radius``,
scale factor 2 for the default glyph of diameter 1) draws them at their true size.
Walls are triangle polydata with a ``wall_id`` cell array so each wall can be
coloured or hidden separately. ``write_pvd`` ties a time series of files
together (ParaView's "collection" format) so a run plays as an animation.

Files use the ASCII data format: larger than base64 but readable, diffable and
parsed back in the tests without any VTK library.
"""
from __future__ import annotations

import os
from xml.sax.saxutils import quoteattr

import numpy as np

_TYPES = {"f": "Float64", "i": "Int64", "u": "UInt64", "b": "UInt8"}


def _data_array(name: str, values: np.ndarray, indent: str = "        ") -> str:
    a = np.asarray(values)
    if a.dtype.kind not in _TYPES:
        raise ValueError(f"array {name!r}: unsupported dtype {a.dtype}")
    if a.dtype.kind == "b":
        a = a.astype(np.uint8)
    ncomp = 1 if a.ndim == 1 else int(np.prod(a.shape[1:]))
    flat = a.reshape(-1)
    if a.dtype.kind == "f":
        body = " ".join(f"{x:.9g}" for x in flat.astype(np.float64))
    else:
        body = " ".join(str(int(x)) for x in flat)
    comp = f' NumberOfComponents="{ncomp}"' if ncomp > 1 else ""
    return (f'{indent}<DataArray type="{_TYPES[a.dtype.kind]}" Name={quoteattr(name)}{comp} format="ascii">'
            f"{body}</DataArray>\n")


def _check_field(name, values, n):
    a = np.asarray(values)
    if a.shape[0] != n:
        raise ValueError(f"field {name!r} has {a.shape[0]} entries, expected {n}")
    return a


def _polydata(points, point_data, cell_data, verts=None, polys=None) -> str:
    points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    n_verts = 0 if verts is None else len(verts)
    n_polys = 0 if polys is None else len(polys)
    out = ['<?xml version="1.0"?>\n',
           '<VTKFile type="PolyData" version="1.0" byte_order="LittleEndian" header_type="UInt64">\n',
           "  <PolyData>\n",
           f'    <Piece NumberOfPoints="{len(points)}" NumberOfVerts="{n_verts}" NumberOfLines="0" '
           f'NumberOfStrips="0" NumberOfPolys="{n_polys}">\n',
           "      <PointData>\n"]
    out += [_data_array(k, v) for k, v in point_data.items()]
    out.append("      </PointData>\n      <CellData>\n")
    out += [_data_array(k, v) for k, v in cell_data.items()]
    out.append("      </CellData>\n      <Points>\n")
    out.append(_data_array("Points", points))
    out.append("      </Points>\n")
    for tag, cells in (("Verts", verts), ("Polys", polys)):
        cells = np.zeros((0, 1), np.int64) if cells is None else np.asarray(cells, dtype=np.int64)
        k = cells.shape[1] if cells.ndim == 2 else 1
        offsets = np.arange(1, len(cells) + 1, dtype=np.int64) * k
        out.append(f"      <{tag}>\n")
        out.append(_data_array("connectivity", cells.reshape(-1)))
        out.append(_data_array("offsets", offsets))
        out.append(f"      </{tag}>\n")
    out.append("    </Piece>\n  </PolyData>\n</VTKFile>\n")
    return "".join(out)


def write_particles_vtp(path: str | os.PathLike, centres_m, radii_m, velocities_m_s=None, body_id=None,
                        extra_point_data: dict | None = None) -> None:
    """Spheres as points: ``radius`` (m), ``velocity`` (m/s, 3 components), ``body_id`` (clump id)."""
    c = np.asarray(centres_m, dtype=np.float64).reshape(-1, 3)
    n = len(c)
    data = {"radius": _check_field("radius", np.asarray(radii_m, dtype=np.float64).reshape(-1), n)}
    v = np.zeros((n, 3)) if velocities_m_s is None else np.asarray(velocities_m_s, dtype=np.float64)
    data["velocity"] = _check_field("velocity", v.reshape(n, 3) if v.size == 3 * n else v, n)
    b = np.arange(n) if body_id is None else np.asarray(body_id, dtype=np.int64)
    data["body_id"] = _check_field("body_id", b, n)
    for k, val in (extra_point_data or {}).items():
        data[k] = _check_field(k, val, n)
    verts = np.arange(n, dtype=np.int64).reshape(-1, 1)
    _write(path, _polydata(c, data, {}, verts=verts))


def write_walls_vtp(path: str | os.PathLike, walls, extra_cell_data: dict | None = None) -> None:
    """Triangle walls: ``walls`` is one (n, 3, 3) array or a list of them; cell array ``wall_id`` = list index."""
    if isinstance(walls, np.ndarray) and walls.ndim == 3:
        walls = [walls]
    tris = [np.asarray(w, dtype=np.float64).reshape(-1, 3, 3) for w in walls]
    allt = np.concatenate(tris) if tris else np.zeros((0, 3, 3))
    wall_id = np.concatenate([np.full(len(t), i, dtype=np.int64) for i, t in enumerate(tris)]) if tris else np.zeros(0, np.int64)
    cell = {"wall_id": wall_id}
    for k, val in (extra_cell_data or {}).items():
        cell[k] = _check_field(k, val, len(allt))
    polys = np.arange(3 * len(allt), dtype=np.int64).reshape(-1, 3)
    _write(path, _polydata(allt.reshape(-1, 3), {}, cell, polys=polys))


def write_pvd(path: str | os.PathLike, entries) -> None:
    """ParaView collection of (time_s, file) pairs; file paths are written relative to the .pvd."""
    base = os.path.dirname(os.path.abspath(path))
    lines = ['<?xml version="1.0"?>\n', '<VTKFile type="Collection" version="1.0" byte_order="LittleEndian">\n',
             "  <Collection>\n"]
    for t, f in entries:
        rel = os.path.relpath(os.path.abspath(f), base)
        lines.append(f'    <DataSet timestep="{float(t):.9g}" group="" part="0" file={quoteattr(rel)}/>\n')
    lines.append("  </Collection>\n</VTKFile>\n")
    _write(path, "".join(lines))


def _write(path, text):
    tmp = f"{path}.tmp"
    with open(tmp, "w", encoding="ascii") as fh:
        fh.write(text)
    os.replace(tmp, path)  # a reader (ParaView, a watcher) never sees a half-written file


def write_packing_vtp(path: str | os.PathLike, packing) -> None:
    """A ``particles.generation.Packing`` (at rest) as sphere points with body ids."""
    centres, radii, body = packing.sphere_positions()
    write_particles_vtp(path, centres, radii, None, body)
