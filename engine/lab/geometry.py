"""Wall sets of the laboratory apparatus, as engine ``WallSpec`` lists (SI, z up, floor at z = 0)."""
from __future__ import annotations

import numpy as np

from engine.config import BoxGeom, ConeGeom, CylinderGeom, DiskGeom, MeshGeom, PlaneGeom, RectangleGeom, WallSpec
from engine.lab.presets import AnchorGeometry, AorGeometry, Fidelity

# the walls whose x-force makes the DST shear force (thesis: floor + cylinder of the bottom half)
BOTTOM_HALF = ("floor", "bottom_cylinder", "bottom_ring")
ANCHOR = ("anchor_tube", "anchor_plate")


def annulus_triangles(centre, inner_radius_m: float, outer_radius_m: float, segments: int = 96) -> np.ndarray:
    """Flat horizontal ring as a triangle mesh (n, 3, 3)."""
    c = np.asarray(centre, dtype=float)
    ang = np.linspace(0.0, 2 * np.pi, segments + 1)
    ring = np.c_[np.cos(ang), np.sin(ang), np.zeros_like(ang)]
    inner = c + inner_radius_m * ring
    outer = c + outer_radius_m * ring
    tris = []
    for k in range(segments):
        tris.append([inner[k], outer[k], outer[k + 1]])
        tris.append([inner[k], outer[k + 1], inner[k + 1]])
    return np.array(tris)


def shear_box_walls(preset: Fidelity, top_height_m: float, wall_kn: float, wall_friction: float,
                    r_min_m: float, ring_width_m: float) -> list[WallSpec]:
    """Split cylindrical container: bottom half (floor, cylinder, outer gap ring) and top half.

    The top cylinder reaches ``top_height_m`` so that a rainfall column above the container is
    enclosed (the thesis extended it to 5 m). The gap rings sit outside the gap (inner edge half a
    smallest radius outside the cylinders, too narrow for any particle) and keep particles from
    escaping through the crescent that opens as the halves part.
    """
    r, zs, gap = preset.container_radius_m, preset.split_height_m, preset.gap_m
    common = dict(normal_stiffness_n_per_m=wall_kn, friction=wall_friction)
    ring_in, ring_out = r + 0.5 * r_min_m, r + ring_width_m
    return [
        WallSpec(name="floor", geometry=DiskGeom(centre_m=(0, 0, 0), normal=(0, 0, 1), radius_m=r), **common),
        WallSpec(name="bottom_cylinder", geometry=CylinderGeom(base_m=(0, 0, 0), radius_m=r, height_m=zs), **common),
        WallSpec(name="bottom_ring", geometry=MeshGeom(triangles_m=annulus_triangles((0, 0, zs), ring_in, ring_out)),
                 **common),
        WallSpec(name="top_cylinder", geometry=CylinderGeom(base_m=(0, 0, zs + gap), radius_m=r,
                                                            height_m=top_height_m - zs - gap), **common),
        WallSpec(name="top_ring", geometry=MeshGeom(triangles_m=annulus_triangles((0, 0, zs + gap), ring_in, ring_out)),
                 **common),
    ]


def lid_wall(preset: Fidelity, z_m: float, wall_kn: float, wall_friction: float) -> WallSpec:
    return WallSpec(name="lid", geometry=DiskGeom(centre_m=(0, 0, z_m), normal=(0, 0, -1),
                                                  radius_m=preset.container_radius_m),
                    normal_stiffness_n_per_m=wall_kn, friction=wall_friction)


def bucket_walls(aor: AorGeometry, column_top_m: float, wall_kn: float, bucket_friction: float,
                 floor_friction: float) -> list[WallSpec]:
    """Floor plane, bottomless frustum bucket, and a cylinder continuing it up while it is filled."""
    return [
        WallSpec(name="floor", geometry=PlaneGeom(point_m=(0, 0, 0), normal=(0, 0, 1)),
                 normal_stiffness_n_per_m=wall_kn, friction=floor_friction),
        WallSpec(name="bucket", geometry=ConeGeom(base_m=(0, 0, 0), radius_bottom_m=aor.bucket_bottom_radius_m,
                                                  radius_top_m=aor.bucket_top_radius_m, height_m=aor.bucket_height_m),
                 normal_stiffness_n_per_m=wall_kn, friction=bucket_friction),
        WallSpec(name="bucket_extension",
                 geometry=CylinderGeom(base_m=(0, 0, aor.bucket_height_m), radius_m=aor.bucket_top_radius_m,
                                       height_m=max(column_top_m - aor.bucket_height_m, 0.01)),
                 normal_stiffness_n_per_m=wall_kn, friction=bucket_friction),
    ]


def anchor_bin_walls(anchor: AnchorGeometry, bin_width_m: float, column_top_m: float, wall_kn: float,
                     bin_friction: float, anchor_friction: float, floor_gap_m: float) -> list[WallSpec]:
    """Square bin (floor + four sides) with the anchor (tube + foot plate) standing at its centre."""
    h = 0.5 * bin_width_m
    zc = 0.5 * column_top_m
    bin_common = dict(normal_stiffness_n_per_m=wall_kn, friction=bin_friction)
    sides = []
    for name, centre, u in (("bin_xm", (-h, 0, zc), (0, 1, 0)), ("bin_xp", (h, 0, zc), (0, 1, 0)),
                            ("bin_ym", (0, -h, zc), (1, 0, 0)), ("bin_yp", (0, h, zc), (1, 0, 0))):
        sides.append(WallSpec(name=name, geometry=RectangleGeom(centre_m=centre, axis_u=u, axis_v=(0, 0, 1),
                                                               half_size_u_m=h, half_size_v_m=zc), **bin_common))
    plate_z = floor_gap_m + 0.5 * anchor.plate_thickness_m
    tube_z = floor_gap_m + anchor.plate_thickness_m + 0.5 * anchor.tube_length_m
    anchor_common = dict(normal_stiffness_n_per_m=wall_kn, friction=anchor_friction)
    return [
        WallSpec(name="floor", geometry=PlaneGeom(point_m=(0, 0, 0), normal=(0, 0, 1)), **bin_common),
        *sides,
        WallSpec(name="anchor_plate", geometry=BoxGeom(
            centre_m=(0, 0, plate_z),
            half_extents_m=(0.5 * anchor.plate_width_m, 0.5 * anchor.plate_width_m, 0.5 * anchor.plate_thickness_m)),
            **anchor_common),
        WallSpec(name="anchor_tube", geometry=BoxGeom(
            centre_m=(0, 0, tube_z),
            half_extents_m=(0.5 * anchor.tube_width_m, 0.5 * anchor.tube_width_m, 0.5 * anchor.tube_length_m)),
            **anchor_common),
    ]
