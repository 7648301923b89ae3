"""VTK XML files parsed back with the standard library (what ParaView's reader expects)."""
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from engine.io import vtk
from engine.particles import generation as G
from engine.particles import templates as T


def parse(path):
    root = ET.parse(path).getroot()
    assert root.get("type") == "PolyData"
    piece = root.find("PolyData/Piece")

    def arrays(tag):
        out = {}
        for a in piece.find(tag).findall("DataArray"):
            dt = float if a.get("type").startswith("Float") else int
            vals = np.array([dt(x) for x in (a.text or "").split()])
            k = int(a.get("NumberOfComponents", "1"))
            out[a.get("Name")] = vals.reshape(-1, k) if k > 1 else vals
        return out

    return piece, arrays


def test_particles_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    c = rng.random((20, 3))
    r = 0.01 + 0.005 * rng.random(20)
    v = rng.normal(size=(20, 3))
    body = np.repeat(np.arange(10), 2)
    f = tmp_path / "p.vtp"
    vtk.write_particles_vtp(f, c, r, v, body, extra_point_data={"speed": np.linalg.norm(v, axis=1)})
    piece, arrays = parse(f)
    assert piece.get("NumberOfPoints") == "20" and piece.get("NumberOfVerts") == "20"
    np.testing.assert_allclose(arrays("Points")["Points"], c, rtol=1e-8)
    pd = arrays("PointData")
    np.testing.assert_allclose(pd["radius"], r, rtol=1e-8)
    np.testing.assert_allclose(pd["velocity"], v, rtol=1e-8)
    np.testing.assert_array_equal(pd["body_id"], body)
    assert set(pd) == {"radius", "velocity", "body_id", "speed"}
    verts = arrays("Verts")
    np.testing.assert_array_equal(verts["connectivity"], np.arange(20))
    np.testing.assert_array_equal(verts["offsets"], np.arange(1, 21))


def test_walls_from_a_list_of_meshes(tmp_path):
    a = np.array([[[0, 0, 0], [1, 0, 0], [0, 1, 0.0]]])
    b = np.array([[[0, 0, 1], [1, 0, 1], [0, 1, 1.0]], [[1, 0, 1], [1, 1, 1], [0, 1, 1.0]]])
    f = tmp_path / "w.vtp"
    vtk.write_walls_vtp(f, [a, b])
    piece, arrays = parse(f)
    assert piece.get("NumberOfPolys") == "3" and piece.get("NumberOfPoints") == "9"
    np.testing.assert_allclose(arrays("Points")["Points"].reshape(-1, 3, 3), np.concatenate([a, b]))
    np.testing.assert_array_equal(arrays("CellData")["wall_id"], [0, 1, 1])
    polys = arrays("Polys")
    np.testing.assert_array_equal(polys["offsets"], [3, 6, 9])
    np.testing.assert_array_equal(polys["connectivity"], np.arange(9))


def test_packing_and_time_series(tmp_path):
    p = G.lattice(T.double_clump(0.01, 0.01, 0.5), G.BoxRegion((0, 0, 0), (0.2, 0.2, 0.2)), count=8)
    f = tmp_path / "pack_0.vtp"
    vtk.write_packing_vtp(f, p)
    _, arrays = parse(f)
    np.testing.assert_array_equal(arrays("PointData")["body_id"], np.repeat(np.arange(8), 2))
    pvd = tmp_path / "run.pvd"
    vtk.write_pvd(pvd, [(0.0, f), (0.5, f)])
    ds = ET.parse(pvd).getroot().findall("Collection/DataSet")
    assert [d.get("timestep") for d in ds] == ["0", "0.5"] and ds[0].get("file") == "pack_0.vtp"


def test_mismatched_field_length_is_rejected(tmp_path):
    with pytest.raises(ValueError, match="radius"):
        vtk.write_particles_vtp(tmp_path / "x.vtp", np.zeros((3, 3)), np.ones(2))
