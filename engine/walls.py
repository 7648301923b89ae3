"""Turn WallSpecs into the kernel's wall arrays, and describe walls for output (VTK)."""
from __future__ import annotations

import numpy as np

from .config import WallSpec
from .state import MODE_KINEMATIC, MODE_SERVO, Walls
from .wallgeom import BOX, DISK, FRUSTUM, MESH, PLANE, RECTANGLE


def _unit(v) -> np.ndarray:
    a = np.asarray(v, dtype=np.float64)
    n = np.linalg.norm(a)
    if not np.isfinite(n) or n == 0.0:
        raise ValueError(f"direction {tuple(v)} must be a non-zero vector")
    return a / n


def frame_from_axis(axis) -> np.ndarray:
    w = _unit(axis)
    helper = np.array([1.0, 0.0, 0.0]) if abs(w[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    u = np.cross(helper, w)
    u /= np.linalg.norm(u)
    return np.array([u, np.cross(w, u), w])


def frame_from_uv(axis_u, axis_v) -> np.ndarray:
    u = _unit(axis_u)
    v = np.asarray(axis_v, dtype=np.float64) - np.dot(axis_v, u) * u
    v = _unit(v)
    return np.array([u, v, np.cross(u, v)])


def _geometry(spec: WallSpec):
    """(kind, origin, frame, par, triangles or None) of one wall."""
    g = spec.geometry
    par = np.zeros(4)
    if g.kind == "plane":
        return PLANE, np.array(g.point_m, float), frame_from_axis(g.normal), par, None
    if g.kind == "disk":
        par[0] = g.radius_m
        return DISK, np.array(g.centre_m, float), frame_from_axis(g.normal), par, None
    if g.kind == "rectangle":
        par[:2] = g.half_size_u_m, g.half_size_v_m
        return RECTANGLE, np.array(g.centre_m, float), frame_from_uv(g.axis_u, g.axis_v), par, None
    if g.kind == "cylinder":
        par[:3] = g.radius_m, g.radius_m, g.height_m
        return FRUSTUM, np.array(g.base_m, float), frame_from_axis(g.axis), par, None
    if g.kind == "cone":
        par[:3] = g.radius_bottom_m, g.radius_top_m, g.height_m
        return FRUSTUM, np.array(g.base_m, float), frame_from_axis(g.axis), par, None
    if g.kind == "box":
        par[:3] = g.half_extents_m
        if min(g.half_extents_m) <= 0:
            raise ValueError(f"wall {spec.name}: box half_extents_m must be positive")
        return BOX, np.array(g.centre_m, float), frame_from_uv(g.axis_u, g.axis_v), par, None
    tri = np.asarray(g.triangles_m, dtype=np.float64)
    return MESH, np.zeros(3), np.eye(3), par, tri


def build_walls(specs: list[WallSpec], n_materials: int, t_now: float = 0.0) -> Walls:
    n = len(specs)
    kind = np.zeros(n, np.int64)
    origin = np.zeros((n, 3))
    frame = np.zeros((n, 3, 3))
    par = np.zeros((n, 4))
    tris, tri_start = [], [0]
    box_lo = np.zeros((n, 3))
    box_hi = np.zeros((n, 3))
    for w, spec in enumerate(specs):
        if spec.material_id >= n_materials:
            raise ValueError(f"wall {spec.name}: material_id {spec.material_id} out of range ({n_materials} materials)")
        kind[w], origin[w], frame[w], par[w], tri = _geometry(spec)
        if tri is not None:
            tris.append(tri)
            box_lo[w] = tri.reshape(-1, 3).min(axis=0)
            box_hi[w] = tri.reshape(-1, 3).max(axis=0)
            tri_start.append(tri_start[-1] + tri.shape[0])
        else:
            tri_start.append(tri_start[-1])
    walls = Walls(
        kind=kind, origin=origin, frame=frame, par=par,
        kn=np.array([s.normal_stiffness_n_per_m for s in specs], float),
        mu=np.array([s.friction for s in specs], float),
        material=np.array([s.material_id for s in specs], np.int64),
        vel=np.zeros((n, 3)), vel_target=np.zeros((n, 3)), ramp_time=np.zeros(n), ramp_start=np.zeros(n),
        mode=np.zeros(n, np.int64), servo_axis=np.zeros((n, 3)), servo_target=np.zeros(n),
        servo_vmax=np.zeros(n), servo_gain=np.zeros(n),
        tri=np.concatenate(tris) if tris else np.zeros((0, 3, 3)),
        tri_start=np.array(tri_start, np.int64), box_lo=box_lo, box_hi=box_hi,
        force=np.zeros((n, 3)), moment=np.zeros((n, 3)), k_sum=np.zeros(n), origin_at_build=origin.copy(),
        omega=np.zeros((n, 3)), centre=origin.copy(), reach=np.zeros(n), swept=np.zeros(n),
    )
    for w, spec in enumerate(specs):
        set_motion(walls, w, spec.velocity_m_s, spec.ramp_time_s, t_now)
        set_rotation(walls, w, spec.angular_velocity_rad_s, spec.rotation_centre_m)
        if spec.servo is not None:
            set_servo(walls, w, spec.servo)
    return walls


def set_motion(walls: Walls, w: int, velocity_m_s, ramp_time_s: float = 0.0, t_now: float = 0.0) -> None:
    walls.mode[w] = MODE_KINEMATIC
    walls.vel_target[w] = np.asarray(velocity_m_s, dtype=np.float64)
    walls.ramp_time[w] = ramp_time_s
    walls.ramp_start[w] = t_now
    if ramp_time_s == 0.0:
        walls.vel[w] = walls.vel_target[w]


def set_rotation(walls: Walls, w: int, angular_velocity_rad_s, centre_m=None) -> None:
    """Spin wall w at a constant angular velocity about an axis through centre_m (None: its reference point)."""
    omega = np.asarray(angular_velocity_rad_s, dtype=np.float64)
    if omega.shape != (3,) or not np.all(np.isfinite(omega)):
        raise ValueError("angular_velocity_rad_s must be three finite numbers")
    walls.omega[w] = omega
    walls.centre[w] = walls.origin[w] if centre_m is None else np.asarray(centre_m, dtype=np.float64)


def mesh_bounds(walls: Walls, w: int) -> None:
    """Refresh the bounding box of a mesh wall (relative to its origin) after it rotated."""
    t = walls.tri[walls.tri_start[w]:walls.tri_start[w + 1]].reshape(-1, 3)
    if t.size:
        walls.box_lo[w] = t.min(axis=0)
        walls.box_hi[w] = t.max(axis=0)


def set_servo(walls: Walls, w: int, servo) -> None:
    walls.mode[w] = MODE_SERVO
    walls.servo_axis[w] = _unit(servo.axis)
    walls.servo_target[w] = servo.target_n()
    walls.servo_vmax[w] = servo.max_speed_m_s
    walls.servo_gain[w] = servo.gain_fraction


def wall_triangles(walls: Walls, w: int, segments: int = 48) -> np.ndarray:
    """A triangle tessellation of wall w at its current position (for VTK output), (n, 3, 3)."""
    kind, o, fr, p = walls.kind[w], walls.origin[w], walls.frame[w], walls.par[w]
    if kind == MESH:
        return walls.tri[walls.tri_start[w]:walls.tri_start[w + 1]] + o
    u, v, ax = fr
    if kind in (PLANE, RECTANGLE):
        a, b = (p[0], p[1]) if kind == RECTANGLE else (1.0, 1.0)
        c = [o + su * a * u + sv * b * v for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        return np.array([[c[0], c[1], c[2]], [c[0], c[2], c[3]]])
    ang = np.linspace(0.0, 2 * np.pi, segments + 1)
    ring = np.cos(ang)[:, None] * u + np.sin(ang)[:, None] * v
    if kind == DISK:
        return np.array([[o, o + p[0] * ring[k], o + p[0] * ring[k + 1]] for k in range(segments)])
    if kind == FRUSTUM:
        lo = o + p[0] * ring
        hi = o + p[2] * ax + p[1] * ring
        out = []
        for k in range(segments):
            out += [[lo[k], lo[k + 1], hi[k + 1]], [lo[k], hi[k + 1], hi[k]]]
        return np.array(out)
    # box: 12 triangles
    corners = np.array([o + sx * p[0] * u + sy * p[1] * v + sz * p[2] * ax
                        for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return np.array([t for a, b, c, d in faces for t in ([corners[a], corners[b], corners[c]],
                                                          [corners[a], corners[c], corners[d]])])
