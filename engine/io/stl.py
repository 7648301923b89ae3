"""STL triangle meshes (ASCII and binary) as (n, 3, 3) float64 arrays: triangle, vertex, xyz.

Units: STL carries none. ``read_stl`` returns the file's numbers times
``scale_to_m`` (default 1, i.e. the file is in metres; pass 1e-3 for CAD files
in millimetres). Facet normals in the file are ignored: walls take their
normal from the vertex order (right-hand rule), which is what CAD writes too.
"""
from __future__ import annotations

import os
import struct

import numpy as np

_BINARY_DTYPE = np.dtype([("normal", "<f4", (3,)), ("vertices", "<f4", (3, 3)), ("attr", "<u2")])


class StlError(ValueError):
    """The file is not a readable STL."""


def _is_binary(data: bytes) -> bool:
    """Binary when the size matches the triangle count, unless the body reads as ASCII facets.

    Some CAD exporters start binary headers with 'solid', so the header alone decides nothing.
    """
    if len(data) < 84:
        return False
    (n,) = struct.unpack("<I", data[80:84])
    if len(data) != 84 + 50 * n:
        return False
    return not (data.lstrip()[:5].lower() == b"solid" and b"vertex" in data[84:4096])


def _parse_ascii(text: str, path) -> np.ndarray:
    tokens = text.split()
    if not tokens or tokens[0].lower() != "solid":
        raise StlError(f"{path}: neither a binary STL (size mismatch) nor an ASCII STL (no 'solid' header)")
    verts = []
    i = 0
    n = len(tokens)
    while i < n:
        if tokens[i].lower() == "vertex":
            if i + 3 >= n:
                raise StlError(f"{path}: truncated 'vertex' line")
            try:
                verts.append((float(tokens[i + 1]), float(tokens[i + 2]), float(tokens[i + 3])))
            except ValueError as exc:
                raise StlError(f"{path}: bad vertex coordinates near token {i}: {exc}") from None
            i += 4
        else:
            i += 1
    if len(verts) % 3:
        raise StlError(f"{path}: {len(verts)} vertices is not a multiple of 3")
    return np.asarray(verts, dtype=np.float64).reshape(-1, 3, 3)


def read_stl(path: str | os.PathLike, scale_to_m: float = 1.0) -> np.ndarray:
    """Triangles (n, 3, 3) in metres from an ASCII or binary STL file."""
    with open(path, "rb") as fh:
        data = fh.read()
    if _is_binary(data):
        (n,) = struct.unpack("<I", data[80:84])
        rec = np.frombuffer(data, dtype=_BINARY_DTYPE, count=n, offset=84)
        tri = rec["vertices"].astype(np.float64)
    else:
        try:
            text = data.decode("ascii")
        except UnicodeDecodeError:
            raise StlError(f"{path}: not ASCII and its size does not match a binary STL") from None
        tri = _parse_ascii(text, path)
    if tri.shape[0] == 0:
        raise StlError(f"{path}: no triangles")
    if not np.all(np.isfinite(tri)):
        raise StlError(f"{path}: non-finite vertex coordinates")
    return tri * float(scale_to_m)


def triangle_normals(triangles: np.ndarray) -> np.ndarray:
    """Unit normals by the right-hand rule; zero for degenerate triangles."""
    t = np.asarray(triangles, dtype=np.float64)
    n = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    norm = np.linalg.norm(n, axis=1, keepdims=True)
    return np.divide(n, norm, out=np.zeros_like(n), where=norm > 0)


def write_stl(path: str | os.PathLike, triangles: np.ndarray, binary: bool = False, name: str = "demcal") -> None:
    """Write (n, 3, 3) triangles (metres) as ASCII (default) or binary STL."""
    tri = np.asarray(triangles, dtype=np.float64)
    if tri.ndim != 3 or tri.shape[1:] != (3, 3):
        raise ValueError(f"triangles must have shape (n, 3, 3), got {tri.shape}")
    normals = triangle_normals(tri)
    if binary:
        rec = np.zeros(len(tri), dtype=_BINARY_DTYPE)
        rec["normal"] = normals
        rec["vertices"] = tri
        header = f"binary STL written by demcal: {name}".encode("ascii")[:80].ljust(80, b" ")
        with open(path, "wb") as fh:
            fh.write(header)
            fh.write(struct.pack("<I", len(tri)))
            fh.write(rec.tobytes())
        return
    lines = [f"solid {name}"]
    for t, n in zip(tri, normals):
        lines.append(f"  facet normal {n[0]:.9e} {n[1]:.9e} {n[2]:.9e}")
        lines.append("    outer loop")
        for v in t:
            lines.append(f"      vertex {v[0]:.17g} {v[1]:.17g} {v[2]:.17g}")
        lines.append("    endloop")
        lines.append("  endfacet")
    lines.append(f"endsolid {name}")
    with open(path, "w", encoding="ascii") as fh:
        fh.write("\n".join(lines) + "\n")


def plate(half_width_m: float, z_m: float = 0.0) -> np.ndarray:
    """A flat square plate of two triangles at height z, normal +z (e.g. a compression lid)."""
    h = float(half_width_m)
    return np.array([
        [[-h, -h, z_m], [h, -h, z_m], [h, h, z_m]],
        [[-h, -h, z_m], [h, h, z_m], [-h, h, z_m]],
    ], dtype=np.float64)
