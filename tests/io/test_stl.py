import numpy as np
import pytest

from engine.io import stl

# a unit right tetrahedron written by hand (ASCII STL as CAD tools write it), metres
ASCII_TET = """solid tet
  facet normal 0 0 -1
    outer loop
      vertex 0 0 0
      vertex 0 1 0
      vertex 1 0 0
    endloop
  endfacet
  facet normal 0 -1 0
    outer loop
      vertex 0 0 0
      vertex 1 0 0
      vertex 0 0 1
    endloop
  endfacet
  facet normal -1 0 0
    outer loop
      vertex 0 0 0
      vertex 0 0 1
      vertex 0 1 0
    endloop
  endfacet
  facet normal 0.577 0.577 0.577
    outer loop
      vertex 1 0 0
      vertex 0 1 0
      vertex 0 0 1
    endloop
  endfacet
endsolid tet
"""


def test_reads_hand_written_ascii_and_normals_follow_vertex_order(tmp_path):
    f = tmp_path / "tet.stl"
    f.write_text(ASCII_TET)
    tri = stl.read_stl(f)
    assert tri.shape == (4, 3, 3) and tri.dtype == np.float64
    np.testing.assert_array_equal(tri[3], [[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    n = stl.triangle_normals(tri)
    np.testing.assert_allclose(n[0], [0, 0, -1])
    np.testing.assert_allclose(n[3], np.ones(3) / np.sqrt(3))
    # closed, outward-oriented surface: divergence theorem gives the tetrahedron's volume 1/6
    vol = np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum() / 6
    assert vol == pytest.approx(1 / 6)
    np.testing.assert_allclose(stl.read_stl(f, scale_to_m=1e-3), tri * 1e-3)


@pytest.mark.parametrize("binary", [False, True])
def test_round_trip(tmp_path, binary):
    rng = np.random.default_rng(0)
    tri = rng.normal(size=(50, 3, 3))
    f = tmp_path / "m.stl"
    stl.write_stl(f, tri, binary=binary)
    back = stl.read_stl(f)
    if binary:  # binary STL stores float32
        assert f.stat().st_size == 84 + 50 * 50
        np.testing.assert_allclose(back, tri, rtol=1e-6, atol=1e-6)
    else:
        np.testing.assert_array_equal(back, tri)


def test_binary_header_starting_with_solid_is_still_binary(tmp_path):
    f = tmp_path / "b.stl"
    stl.write_stl(f, stl.plate(0.35, 0.1), binary=True)
    data = bytearray(f.read_bytes())
    data[:5] = b"solid"
    f.write_bytes(bytes(data))
    np.testing.assert_allclose(stl.read_stl(f), stl.plate(0.35, 0.1))


def test_plate_is_two_triangles_with_upward_normals():
    p = stl.plate(0.35, 0.2)
    np.testing.assert_allclose(stl.triangle_normals(p), [[0, 0, 1], [0, 0, 1]])
    area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1).sum()
    assert area == pytest.approx(0.7 * 0.7)


def test_garbage_gives_a_clear_error(tmp_path):
    f = tmp_path / "x.stl"
    f.write_bytes(b"\xff\xfe not an stl at all")
    with pytest.raises(stl.StlError, match="x.stl"):
        stl.read_stl(f)
    f.write_text("solid empty\nendsolid empty\n")
    with pytest.raises(stl.StlError, match="no triangles"):
        stl.read_stl(f)
