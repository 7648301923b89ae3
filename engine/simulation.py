"""The engine's public object: a Simulation configured from plain data, driven by procedures.

All heavy work runs in numba kernels between Python-level chunks (neighbour rebuilds, callbacks),
so the per-step Python overhead is nil. Everything here is SI.
"""
from __future__ import annotations

import json
import math
from typing import Callable

import numba
import numpy as np

from . import blocks, neighbors
from .config import MaterialSpec, ServoSpec, SimulationConfig, WallSpec
from .effects import get as get_effect
from .history import PendingHistory
from .kernelgen import layout_for, load_kernel
from .ordering import cell_order, permute, sphere_rows
from .pairtable import build_props
from .state import (Bodies, Pairs, Spheres, WallContacts, Walls, empty_bodies, empty_pairs, empty_spheres,
                    empty_wall_contacts)
from .timestep import TimestepReport, critical_timestep, effect_limits, rotation_factor
from .wallgeom import MESH
from .walls import build_walls, mesh_bounds, set_motion, set_rotation, set_servo, wall_triangles

ProgressCallback = Callable[["Simulation"], "bool | None"]
_REC = 10  # t, origin(3), force(3), moment(3)
CHECKPOINT_FORMAT = 3  # 3: pair constants, per-sphere accumulators and row blocks (no pair load array)



class Simulation:
    """A DEM simulation: bodies (spheres and rigid clumps), walls, contact law + effects."""

    def __init__(self, config: SimulationConfig | dict | None = None):
        if config is None:
            config = SimulationConfig()
        self.config = config if isinstance(config, SimulationConfig) else SimulationConfig.model_validate(config)
        self.n_materials = len(self.config.materials)
        self.layout = layout_for([e.name for e in self.config.effects] + list(self.config.compiled_effects))
        for e in self.config.effects:  # validate parameters now, with the field named
            get_effect(e.name).params_model.model_validate(e.params)
        self.props = build_props(self.config, self.layout)
        self.bodies: Bodies = empty_bodies()
        self.spheres: Spheres = empty_spheres()
        self.wall_specs: list[WallSpec] = []
        self.walls: Walls = build_walls([], self.n_materials)
        self.pairs: Pairs = empty_pairs(0, self.layout.n_hist)
        self.wall_contacts: WallContacts = empty_wall_contacts(0, self.layout.n_hist)
        g = self.config.gravity_m_s2
        self._scal = np.array([0.0, 0.0, g[0], g[1], g[2], 0.0,
                               1.0 if self.config.limit_normal_force_to_repulsive else 0.0])
        self._istate = np.array([2, 0, 0], np.int64)
        self._records: list[np.ndarray] = []
        self._body_template = np.zeros(0, np.int64)
        # public body id of each internal body (bodies are kept in cell order internally; see ordering.py)
        self._body_user = np.zeros(0, np.int64)
        self._user_rows: tuple[np.ndarray, np.ndarray] | None = None
        self._rebuilds_since_order = 0
        # history to carry into the next rebuild when the numbering changed; None: the current lists
        self._pending: PendingHistory | None = None
        self._kernel = None
        self._report: TimestepReport | None = None
        self._stale = True

    # ------------------------------------------------------------------ building
    def add_packing(self, packing, material_id: int = 0, velocities_m_s=None) -> np.ndarray:
        """Add the bodies of an engine.particles Packing; returns their body ids."""
        return self.add_bodies(packing.templates, packing.template_index, packing.positions_m,
                               packing.orientations, material_id, velocities_m_s)

    def add_bodies(self, templates, template_index, positions_m, orientations=None, material_id: int = 0,
                   velocities_m_s=None, angular_velocities_rad_s=None) -> np.ndarray:
        """Add rigid bodies made from ClumpTemplates (a sphere is a one-sphere template)."""
        if not 0 <= material_id < self.n_materials:
            raise ValueError(f"material_id {material_id} out of range ({self.n_materials} materials)")
        tidx = np.asarray(template_index, dtype=np.int64)
        pos = np.asarray(positions_m, dtype=np.float64).reshape(-1, 3)
        n = pos.shape[0]
        if tidx.shape != (n,) or (n and (tidx.min() < 0 or tidx.max() >= len(templates))):
            raise ValueError("template_index must hold one valid template index per position")
        rho = self.config.materials[material_id].density_kg_m3
        offs = [np.asarray(templates[t].sphere_offsets_m, float).reshape(-1, 3) for t in tidx]
        return self._append_bodies(
            pos, tidx, np.array([len(templates[t].sphere_radii_m) for t in tidx], np.int64),
            np.concatenate(offs) if offs else np.zeros((0, 3)),
            np.concatenate([np.asarray(templates[t].sphere_radii_m, float) for t in tidx]) if n else np.zeros(0),
            np.array([rho * templates[t].volume_m3 for t in tidx]),
            np.array([rho * np.asarray(templates[t].principal_inertia_per_density_m5, float) for t in tidx]),
            np.array([o.shape[0] > 1 or bool(np.any(o != 0.0)) for o in offs], np.bool_),
            orientations, material_id, velocities_m_s, angular_velocities_rad_s)

    def _append_bodies(self, pos, tidx, counts, offset, sphere_radii, mass, inertia, is_clump, orientations,
                       material_id, velocities_m_s, angular_velocities_rad_s) -> np.ndarray:
        """Append n bodies given per body (template index, sphere count, mass, principal inertia, clump
        flag) and per sphere (offset, radius), in arrays: add_bodies fills them from templates,
        add_spheres directly (no Python object per sphere)."""
        n = pos.shape[0]
        quat = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1)) if orientations is None else \
            np.asarray(orientations, dtype=np.float64).reshape(n, 4)
        quat = quat / np.linalg.norm(quat, axis=1)[:, None]
        mat = self.config.materials[material_id]
        b_old = self.bodies
        s_old = self.spheres
        nb0, ns0 = b_old.pos.shape[0], s_old.radius.shape[0]
        vel = np.zeros((n, 3)) if velocities_m_s is None else np.asarray(velocities_m_s, float).reshape(n, 3)
        om = np.zeros((n, 3)) if angular_velocities_rad_s is None else \
            np.asarray(angular_velocities_rad_s, float).reshape(n, 3)
        start = np.concatenate([b_old.sphere_start, ns0 + np.cumsum(counts)])
        self.bodies = Bodies(
            pos=np.concatenate([b_old.pos, pos]), vel=np.concatenate([b_old.vel, vel]),
            quat=np.concatenate([b_old.quat, quat]), omega=np.concatenate([b_old.omega, om]),
            mass=np.concatenate([b_old.mass, mass]), inertia=np.concatenate([b_old.inertia, inertia.reshape(n, 3)]),
            force=np.zeros((nb0 + n, 3)), torque=np.zeros((nb0 + n, 3)), sphere_start=start.astype(np.int64),
            is_clump=np.concatenate([b_old.is_clump, is_clump]),
            local_damping=np.concatenate([b_old.local_damping, np.full(n, mat.local_damping)]),
        )
        n_new = int(counts.sum())
        body_ids = np.repeat(np.arange(nb0, nb0 + n, dtype=np.int64), counts)
        self.spheres = Spheres(
            body=np.concatenate([s_old.body, body_ids]), offset=np.concatenate([s_old.offset, offset]),
            radius=np.concatenate([s_old.radius, sphere_radii]),
            pos=np.zeros((ns0 + n_new, 3)), vel=np.zeros((ns0 + n_new, 3)),
            material=np.concatenate([s_old.material, np.full(n_new, material_id, np.int64)]),
            kp=np.concatenate([s_old.kp, np.full(n_new, mat.normal_stiffness_n_per_m)]),
            force=np.zeros((ns0 + n_new, 3)), torque=np.zeros((ns0 + n_new, 3)),
            pos_at_build=np.zeros((ns0 + n_new, 3)),
        )
        self._body_template = np.concatenate([self._body_template, tidx])
        self._body_user = np.concatenate([self._body_user, np.arange(nb0, nb0 + n, dtype=np.int64)])
        self._after_topology_change(np.arange(ns0, dtype=np.int64), ns0)
        return np.arange(nb0, nb0 + n)

    def add_spheres(self, positions_m, radii_m, material_id: int = 0, velocities_m_s=None) -> np.ndarray:
        """Convenience: add single spheres without building templates."""
        radii = np.asarray(radii_m, dtype=np.float64).reshape(-1)
        pos = np.asarray(positions_m, dtype=np.float64).reshape(-1, 3)
        if radii.shape[0] != pos.shape[0] or np.any(radii <= 0):
            raise ValueError("radii_m must be positive, one per position")
        if not 0 <= material_id < self.n_materials:
            raise ValueError(f"material_id {material_id} out of range ({self.n_materials} materials)")
        # What a one-sphere template per radius would give, built as arrays at once (a Python object and
        # small arrays per sphere made this the memory peak of a run: 1,185 bytes per sphere at 200,000).
        # np.power with an array exponent calls pow() as the templates' float ** does; `radii ** 2` would
        # square, which differs in the last bit for about 1 radius in 1,200.
        n = radii.shape[0]
        volume = 4.0 / 3.0 * math.pi * np.power(radii, np.full_like(radii, 3.0))
        rho = self.config.materials[material_id].density_kg_m3
        inertia = rho * np.repeat((0.4 * volume * np.power(radii, np.full_like(radii, 2.0)))[:, None], 3, axis=1)
        return self._append_bodies(pos, np.arange(n, dtype=np.int64), np.ones(n, np.int64), np.zeros((n, 3)),
                                   radii.copy(), rho * volume, inertia, np.zeros(n, np.bool_), None, material_id,
                                   velocities_m_s, None)

    def remove_bodies(self, mask) -> None:
        """Delete bodies where mask is True (e.g. levelling a packing); contact history of the rest is kept."""
        mask = np.asarray(mask, dtype=bool)
        b, s = self.bodies, self.spheres
        if mask.shape != (b.pos.shape[0],):
            raise ValueError(f"mask must have one entry per body ({b.pos.shape[0]})")
        new_user_id = np.cumsum(~mask) - 1
        mask = mask[self._body_user]  # public order -> internal order
        keep_b = ~mask
        keep_s = keep_b[s.body]
        new_body_id = np.cumsum(keep_b) - 1
        counts = np.diff(b.sphere_start)[keep_b]
        self.bodies = Bodies(
            pos=b.pos[keep_b], vel=b.vel[keep_b], quat=b.quat[keep_b], omega=b.omega[keep_b], mass=b.mass[keep_b],
            inertia=b.inertia[keep_b], force=b.force[keep_b], torque=b.torque[keep_b],
            sphere_start=np.concatenate([[0], np.cumsum(counts)]).astype(np.int64), is_clump=b.is_clump[keep_b],
            local_damping=b.local_damping[keep_b])
        self.spheres = Spheres(*[a[keep_s] for a in s])
        self.spheres = self.spheres._replace(body=new_body_id[self.spheres.body].astype(np.int64))
        self._body_template = self._body_template[keep_b]
        self._body_user = new_user_id[self._body_user[keep_b]].astype(np.int64)
        self._after_topology_change(np.nonzero(keep_s)[0], keep_s.shape[0])

    # material fields that act only through the pair table: changing them needs no new time step
    # and no per-body data (density and stiffness do)
    MUTABLE_MATERIAL_FIELDS = ("friction", "damping_ratio_normal", "damping_ratio_shear")

    def set_material(self, material_id: int, **changes) -> None:
        """Change a material's friction or damping between runs, e.g. a packing prepared at low friction
        and tested at the calibrated one. Contact history is kept: a sticking contact stays stuck."""
        if not 0 <= material_id < self.n_materials:
            raise ValueError(f"material_id {material_id} out of range ({self.n_materials} materials)")
        bad = sorted(set(changes) - set(self.MUTABLE_MATERIAL_FIELDS))
        if bad:
            raise ValueError(f"cannot change {bad} of a material in a running simulation; only "
                             f"{list(self.MUTABLE_MATERIAL_FIELDS)}")
        materials = list(self.config.materials)
        materials[material_id] = MaterialSpec.model_validate({**materials[material_id].model_dump(), **changes})
        self.config = self.config.model_copy(update={"materials": materials})
        self.props = build_props(self.config, self.layout)

    def add_wall(self, spec: WallSpec | dict) -> int:
        spec = spec if isinstance(spec, WallSpec) else WallSpec.model_validate(spec)
        if any(w.name == spec.name for w in self.wall_specs):
            raise ValueError(f"a wall named {spec.name!r} exists already")
        new = build_walls(self.wall_specs + [spec], self.n_materials, self.time_s)
        n_old = self.n_walls
        self._install_walls(new, np.arange(n_old, dtype=np.int64), np.arange(n_old, dtype=np.int64))
        self.wall_specs.append(spec)
        return n_old

    def remove_wall(self, name: str) -> None:
        """Take a wall away (e.g. lift a bucket off, open a box); the other walls keep their state and history."""
        w = self.wall_index(name)
        keep = np.array([k for k in range(self.n_walls) if k != w], np.int64)
        specs = [s for k, s in enumerate(self.wall_specs) if k != w]
        new = build_walls(specs, self.n_materials, self.time_s)
        self._install_walls(new, keep, np.arange(keep.size, dtype=np.int64))
        self.wall_specs = specs
        self._records = [r[:, keep[keep < r.shape[1]]] if r.shape[1] > w else r for r in self._records]

    def _install_walls(self, new, old_ids: np.ndarray, new_ids: np.ndarray) -> None:
        """Switch to wall arrays `new` in which old wall old_ids[k] is new_ids[k]: carry its motion state,
        its current (possibly rotated) geometry and its contacts' history."""
        old = self.walls
        for name in ("origin", "vel", "vel_target", "ramp_time", "ramp_start", "mode", "servo_axis",
                     "servo_target", "servo_vmax", "servo_gain", "force", "moment", "k_sum", "origin_at_build",
                     "frame", "omega", "centre", "reach", "swept", "box_lo", "box_hi"):
            getattr(new, name)[new_ids] = getattr(old, name)[old_ids]
        wall_remap = np.full(old.kind.shape[0], -1, np.int64)
        wall_remap[old_ids] = new_ids
        tri_remap = np.full(old.tri.shape[0], -1, np.int64)
        for o, n in zip(old_ids, new_ids):
            a, b = old.tri_start[o], old.tri_start[o + 1]
            new.tri[new.tri_start[n]:new.tri_start[n] + (b - a)] = old.tri[a:b]
            tri_remap[a:b] = np.arange(new.tri_start[n], new.tri_start[n] + (b - a))
        self.walls = new
        ident = np.arange(self.n_spheres, dtype=np.int64)
        self._after_topology_change(ident, self.n_spheres, wall_remap, tri_remap)

    def _after_topology_change(self, old_sphere_index: np.ndarray, n_old: int, wall_remap=None,
                               tri_remap=None) -> None:
        """Re-index contact history to the new sphere (and wall) numbering and force a rebuild."""
        remap = np.full(n_old, -1, np.int64)
        remap[old_sphere_index] = np.arange(old_sphere_index.size)
        pending = self._pending or PendingHistory.from_lists(self.pairs, self.wall_contacts)
        self._pending = pending.remapped(remap, wall_remap, tri_remap)
        self._user_rows = None
        self._stale = True
        self._report = None
        self._istate[0] = 2
        if self.n_spheres:
            self._update_spheres()

    def _n_elements(self) -> int:
        return self.n_walls + self.walls.tri.shape[0]

    def _update_spheres(self) -> None:
        b, s = self.bodies, self.spheres
        from .integrate import drift
        drift(b.pos, b.vel, b.quat, b.omega, b.is_clump, b.sphere_start, s.offset, s.pos, s.vel, 0.0)

    # ------------------------------------------------------------------ walls
    def wall_index(self, name: str) -> int:
        for k, w in enumerate(self.wall_specs):
            if w.name == name:
                return k
        raise KeyError(f"no wall named {name!r}; walls: {[w.name for w in self.wall_specs]}")

    def set_wall_velocity(self, name: str, velocity_m_s, ramp_time_s: float = 0.0) -> None:
        """Prescribed translation velocity (servo off), reached linearly over ramp_time_s."""
        set_motion(self.walls, self.wall_index(name), velocity_m_s, ramp_time_s, self.time_s)

    def set_wall_servo(self, name: str, servo: ServoSpec | dict) -> None:
        servo = servo if isinstance(servo, ServoSpec) else ServoSpec.model_validate(servo)
        set_servo(self.walls, self.wall_index(name), servo)

    def set_wall_rotation(self, name: str, angular_velocity_rad_s, centre_m=None) -> None:
        """Spin a wall rigidly about an axis through centre_m (None: its reference point), rad/s."""
        set_rotation(self.walls, self.wall_index(name), angular_velocity_rad_s, centre_m)
        self._stale = True

    def wall_frame(self, name: str) -> np.ndarray:
        """Rows: the wall's current local axes u, v, w (w is a plane's normal or a cylinder's axis)."""
        return self.walls.frame[self.wall_index(name)].copy()

    def translate_wall(self, name: str, displacement_m) -> None:
        w = self.wall_index(name)
        self.walls.origin[w] += np.asarray(displacement_m, dtype=np.float64)
        self.walls.centre[w] += np.asarray(displacement_m, dtype=np.float64)
        self._stale = True

    def wall_position(self, name: str) -> np.ndarray:
        """The wall's reference point (plane point, disk/box centre, cylinder/cone base, mesh offset)."""
        return self.walls.origin[self.wall_index(name)].copy()

    def wall_velocity(self, name: str) -> np.ndarray:
        return self.walls.vel[self.wall_index(name)].copy()

    def wall_force(self, name: str) -> np.ndarray:
        """Resultant force the particles exert on the wall at the last step, N."""
        return self.walls.force[self.wall_index(name)].copy()

    def wall_moment(self, name: str) -> np.ndarray:
        """Resultant moment about the wall's reference point, N m."""
        return self.walls.moment[self.wall_index(name)].copy()

    def wall_history(self, name: str) -> dict[str, np.ndarray]:
        """Time series sampled every config.record_every steps: time_s, position_m, force_n, moment_nm."""
        w = self.wall_index(name)
        # remove_wall drops its column from older records, so index w is the same wall in all of them
        parts = [r[:, w] for r in self._records if r.shape[1] > w]
        rec = np.concatenate(parts) if parts else np.zeros((0, _REC))
        return {"time_s": rec[:, 0], "position_m": rec[:, 1:4], "force_n": rec[:, 4:7], "moment_nm": rec[:, 7:10]}

    def wall_contact_loads(self, name: str) -> dict[str, np.ndarray]:
        """Active contacts on a wall at the last step: contact points_m (k, 3), forces_n on the wall
        (k, 3) and sphere ids (k,); e.g. for wall stress against depth."""
        w = self.wall_index(name)
        wc = self.wall_contacts
        sel = (wc.wall == w) & (wc.k > 0.0)
        sphere = np.repeat(np.arange(wc.start.shape[0] - 1), np.diff(wc.start))
        public = np.empty(self.n_spheres, np.int64)
        public[self._rows()[1]] = np.arange(self.n_spheres)
        return {"points_m": wc.point[sel].copy(), "forces_n": wc.force[sel].copy(),
                "sphere_ids": public[sphere[sel]]}

    def clear_wall_history(self) -> None:
        self._records = []

    def wall_triangles(self, name: str) -> np.ndarray:
        """Triangulated wall surface at its current position, (n, 3, 3), for VTK output."""
        return wall_triangles(self.walls, self.wall_index(name))

    # ------------------------------------------------------------------ time step
    def timestep_report(self) -> TimestepReport:
        if self._report is None:
            self._report = self._compute_timestep()
        return self._report

    @property
    def timestep_s(self) -> float:
        return self.timestep_report().timestep_s

    def _compute_timestep(self) -> TimestepReport:
        if self.n_bodies == 0:
            raise ValueError("add particles before asking for the time step")
        b, s = self.bodies, self.spheres
        reach = np.zeros(self.n_bodies)
        dist = np.linalg.norm(s.offset, axis=1) + s.radius
        np.maximum.at(reach, s.body, dist)
        rot = rotation_factor(b.mass, b.inertia, reach)
        active = [(spec.name, get_effect(spec.name), get_effect(spec.name).params_model.model_validate(spec.params))
                  for spec in self.config.effects]
        rho = min(m.density_kg_m3 for m in self.config.materials)
        extra, stiff = effect_limits(active, rho, float(s.radius.min()))
        crit, mode = critical_timestep(b.mass, rot, s.kp, s.body, self.walls.kn, self.props, self.n_materials, extra,
                                       stiff)
        user = self.config.timestep_s
        if user is not None:
            if user > crit:
                raise ValueError(
                    f"timestep_s = {user:.4g} s is above the critical time step {crit:.4g} s (limited by the "
                    f"{mode} mode); use at most {self.config.safety_factor * crit:.4g} s "
                    f"(safety_factor x critical) or leave timestep_s unset")
            dt = user
        else:
            dt = self.config.safety_factor * crit
        return TimestepReport(critical_s=crit, timestep_s=dt, limiting_mode=mode,
                              safety_factor=self.config.safety_factor)

    # ------------------------------------------------------------------ running
    def _skin(self) -> float:
        return self.config.skin_m if self.config.skin_m is not None else 0.5 * float(self.spheres.radius.min())

    def _rebuild(self) -> None:
        s, w = self.spheres, self.walls
        n = self.n_spheres
        skin = self._skin()
        if not np.isfinite(s.pos).all():
            bad = int(self._body_user[s.body[np.nonzero(~np.isfinite(s.pos).all(axis=1))[0][0]]])
            raise FloatingPointError(
                f"body {bad} has a non-finite position at t = {self.time_s:.6g} s: the run became unstable "
                "(time step too large for the stiffness or damping, a wall moved through particles, or two "
                "spheres of different bodies placed at the same centre)")
        every = self.config.reorder_every_rebuilds
        if every and self._rebuilds_since_order % every == 0:
            self._reorder(skin)
            s = self.spheres
        self._rebuilds_since_order += 1
        pending = self._pending or PendingHistory.from_lists(self.pairs, self.wall_contacts)
        # the old lists live on only through `pending`: let their other arrays go before the new
        # lists are built, so the rebuild holds less at once
        self.pairs = self.wall_contacts = None
        for k in np.nonzero(np.any(w.omega != 0.0, axis=1))[0]:
            # how far from its axis a rotating wall can meet a sphere: bounds the surface's sweep per step
            w.reach[k] = float(np.sqrt(((s.pos - w.centre[k]) ** 2).sum(axis=1).max())) + skin if n else 0.0
            if w.kind[k] == MESH:
                mesh_bounds(w, k)
        w.swept[:] = 0.0
        pi, pj, row_start = neighbors.build_pairs(s.pos, s.radius, s.body, skin)
        old_key, old_hist = pending.pair_lookup(n)
        hist = neighbors.carry_history(old_key, old_hist, neighbors.pair_keys(pi, pj, n), self.layout.n_hist)
        # k marks carried history (nonzero wherever a history row is) until the next force evaluation
        # writes the contact stiffness: the pair pass clears a separated pair only where k is nonzero
        mark = np.any(hist != 0.0, axis=1).astype(np.float64)
        self.pairs = Pairs(pi, pj, row_start, hist, blocks.pair_constants(pi, pj, s.kp, s.body, self.bodies.mass),
                           mark, np.zeros((n, 6)), blocks.block_partition(pi, pj, n))
        start, wall, tri = neighbors.build_wall_list(s.pos, s.radius, skin, w.kind, w.origin, w.frame, w.par,
                                                     w.tri_start, w.tri, w.box_lo, w.box_hi)
        wkey = neighbors.wall_keys(start, wall, tri, self.n_walls, self._n_elements())
        old_key, old_hist = pending.wall_lookup(self.n_walls, self._n_elements())
        whist = neighbors.carry_history(old_key, old_hist, wkey, self.layout.n_hist)
        k = wall.shape[0]
        self.wall_contacts = WallContacts(start, wall, tri, whist, np.zeros((k, 3)), np.zeros((k, 3)), np.zeros(k))
        self._pending = None
        s.pos_at_build[:] = s.pos
        w.origin_at_build[:] = w.origin
        self._stale = False

    def _reorder(self, skin: float) -> None:
        """Renumber bodies in cell order (public ids unchanged); history follows the spheres."""
        order = cell_order(self.bodies.pos, 2.0 * float(self.spheres.radius.max()) + skin)
        if np.array_equal(order, np.arange(order.size)):
            return
        pending = self._pending or PendingHistory.from_lists(self.pairs, self.wall_contacts)
        self.bodies, self.spheres, remap = permute(self.bodies, self.spheres, order)
        self._pending = pending.remapped(remap)
        self._body_template = self._body_template[order]
        self._body_user = self._body_user[order]
        self._user_rows = None

    def _rows(self) -> tuple[np.ndarray, np.ndarray]:
        """(internal body rows, internal sphere rows) in public order."""
        if self._user_rows is None:
            bodies = np.argsort(self._body_user, kind="stable").astype(np.int64)
            self._user_rows = (bodies, sphere_rows(self.bodies.sphere_start, bodies))
        return self._user_rows

    def run(self, duration_s: float | None = None, steps: int | None = None,
            callback: ProgressCallback | None = None, callback_every_s: float | None = None) -> int:
        """Advance by duration_s (rounded to whole steps) or by `steps`; returns the steps taken.

        `callback(sim)` is called every callback_every_s of simulated time (default: about every 2,000
        steps) and at the end; returning True stops the run early.
        """
        if self.n_bodies == 0:
            raise ValueError("the simulation has no particles; add_packing or add_spheres first")
        dt = self.timestep_s
        if (duration_s is None) == (steps is None):
            raise ValueError("give exactly one of duration_s or steps")
        total = int(round(duration_s / dt)) if steps is None else int(steps)
        if total < 0:
            raise ValueError("duration_s / steps must not be negative")
        threads_before = numba.get_num_threads()
        threads = self.config.threads or threads_before
        if self.n_spheres < self.config.serial_below_spheres:
            # waking worker threads twice a step costs more than a small system's work
            threads = 1
        numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
        try:
            return self._run(total, dt, callback, callback_every_s)
        finally:
            numba.set_num_threads(threads_before)

    @property
    def kernel(self):
        """The compiled kernel module of this simulation's layout, loaded (or compiled) on first use.
        The run loop calls its ``advance``; its pieces (pair pass, body pass, wall resultants) are
        reachable here for benchmarks that time them apart (bench/kernel_pieces.py)."""
        if self._kernel is None:
            self._kernel = load_kernel(self.layout, self.config.kernel_cache_dir)
        return self._kernel

    def rebuild_neighbours(self) -> None:
        """Rebuild the candidate-pair and wall-contact lists now. The run loop does this by itself
        when a sphere has moved half the skin; this is for benchmarks that time one rebuild."""
        self._rebuild()

    def _run(self, total, dt, callback, callback_every_s) -> int:
        kernel = self.kernel
        self._scal[0] = dt
        self._scal[5] = self._skin()
        every = max(1, int(round(callback_every_s / dt))) if callback_every_s else 2000
        rec_every = self.config.record_every
        done = 0
        while done < total or self._istate[0] == 2:
            if self._stale:
                self._rebuild()
            chunk = min(total - done, every)
            rec = np.zeros((chunk // rec_every + 2, self.n_walls, _REC))
            self._istate[2] = 0
            k, flag = kernel.advance(self.bodies, self.spheres, self.walls, self.pairs, self.wall_contacts,
                                     self.props, self.n_materials, self._scal, self._istate, chunk, rec, rec_every)
            if self._istate[2]:
                self._records.append(rec[:self._istate[2]].copy())
            done += k
            if flag:
                self._stale = True
                continue
            if callback is not None and callback(self):
                break
            if chunk == 0:
                break
        return done

    # ------------------------------------------------------------------ state access
    @property
    def time_s(self) -> float:
        return float(self._scal[1])

    @property
    def step(self) -> int:
        return int(self._istate[1])

    @property
    def n_bodies(self) -> int:
        return int(self.bodies.pos.shape[0])

    @property
    def n_spheres(self) -> int:
        return int(self.spheres.radius.shape[0])

    @property
    def n_walls(self) -> int:
        return int(self.walls.kind.shape[0])

    def positions_m(self) -> np.ndarray:
        """Body centres of mass, (n_bodies, 3), in public body order (a copy)."""
        return self.bodies.pos[self._rows()[0]]

    def velocities_m_s(self) -> np.ndarray:
        return self.bodies.vel[self._rows()[0]]

    def angular_velocities_rad_s(self) -> np.ndarray:
        return self.bodies.omega[self._rows()[0]]

    def orientations(self) -> np.ndarray:
        """Unit quaternions (w, x, y, z), body -> world."""
        return self.bodies.quat[self._rows()[0]]

    def body_masses_kg(self) -> np.ndarray:
        return self.bodies.mass[self._rows()[0]]

    def body_template_index(self) -> np.ndarray:
        return self._body_template[self._rows()[0]]

    def sphere_positions_m(self) -> np.ndarray:
        """Sphere centres, grouped by body in public body order."""
        return self.spheres.pos[self._rows()[1]]

    def sphere_velocities_m_s(self) -> np.ndarray:
        return self.spheres.vel[self._rows()[1]]

    def sphere_radii_m(self) -> np.ndarray:
        return self.spheres.radius[self._rows()[1]]

    def sphere_body_ids(self) -> np.ndarray:
        """Public body id of every sphere (same order as sphere_positions_m)."""
        return self._body_user[self.spheres.body[self._rows()[1]]]

    def set_velocities(self, velocities_m_s, angular_velocities_rad_s=None) -> None:
        rows = self._rows()[0]
        self.bodies.vel[rows] = np.asarray(velocities_m_s, dtype=np.float64).reshape(-1, 3)
        if angular_velocities_rad_s is not None:
            self.bodies.omega[rows] = np.asarray(angular_velocities_rad_s, dtype=np.float64).reshape(-1, 3)
        self._update_spheres()

    def kinetic_energy(self) -> float:
        """Translational + rotational kinetic energy, J."""
        b = self.bodies
        trans = 0.5 * float(np.sum(b.mass * np.sum(b.vel ** 2, axis=1)))
        return trans + self.rotational_energy()

    def rotational_energy(self) -> float:
        b = self.bodies
        w_body = _rotate_inverse(b.quat, b.omega)
        w_body = np.where(b.is_clump[:, None], w_body, b.omega)
        return 0.5 * float(np.sum(b.inertia * w_body ** 2))

    def contact_count(self) -> tuple[int, int]:
        """(particle-particle, particle-wall) contacts active at the last force evaluation."""
        pp = int(np.count_nonzero(self.pairs.k))
        pw = int(np.count_nonzero(self.wall_contacts.k))
        return pp, pw

    def output_frame(self) -> dict:
        """What a VTK writer needs: spheres (position, radius, velocity, body id) and wall triangles."""
        return {
            "time_s": self.time_s,
            "sphere_positions_m": self.sphere_positions_m(),
            "sphere_radii_m": self.sphere_radii_m(),
            "sphere_velocities_m_s": self.sphere_velocities_m_s(),
            "sphere_body_ids": self.sphere_body_ids(),
            "walls": {w.name: self.wall_triangles(w.name) for w in self.wall_specs},
        }

    # ------------------------------------------------------------------ checkpoints
    def checkpoint(self) -> dict[str, np.ndarray]:
        """The full state (bodies, walls and their motion, contact history, time) as a dict of arrays."""
        out: dict[str, np.ndarray] = {"config_json": np.array(self.config.model_dump_json()),
                                      "walls_json": np.array(json.dumps([_wall_json(w) for w in self.wall_specs])),
                                      "scal": self._scal.copy(), "istate": self._istate.copy(),
                                      "body_template": self._body_template.copy(),
                                      "body_user": self._body_user.copy(),
                                      "rebuilds_since_order": np.array(self._rebuilds_since_order),
                                      "format": np.array(CHECKPOINT_FORMAT)}
        for prefix, tup in (("b_", self.bodies), ("s_", self.spheres), ("w_", self.walls), ("p_", self.pairs),
                            ("c_", self.wall_contacts)):
            for name, arr in zip(tup._fields, tup):
                out[prefix + name] = np.array(arr, copy=True)
        if self._pending is not None:
            out.update(self._pending.to_arrays("pending_"))
        out["stale"] = np.array(self._stale)
        return out

    def save(self, path) -> None:
        np.savez_compressed(path, **self.checkpoint())

    @classmethod
    def from_checkpoint(cls, state) -> "Simulation":
        """Rebuild a Simulation from checkpoint() output or a file written by save()."""
        if not isinstance(state, dict):
            with np.load(state, allow_pickle=False) as data:
                state = {k: data[k] for k in data.files}
        sim = cls(SimulationConfig.model_validate_json(str(state["config_json"])))
        sim.restore(state)
        return sim

    def restore(self, state: dict) -> None:
        """Put back a checkpoint taken from a simulation with the same materials and effects."""
        found = int(state["format"]) if "format" in state else 1
        if found != CHECKPOINT_FORMAT:
            raise ValueError(f"checkpoint format {found} is not this engine's ({CHECKPOINT_FORMAT}); "
                             "re-run the step that wrote it")
        self._scal[:] = state["scal"]
        self._istate[:] = state["istate"]
        self._body_template = state["body_template"].copy()
        self._body_user = state["body_user"].copy()
        self._rebuilds_since_order = int(state["rebuilds_since_order"])
        self._user_rows = None
        self.wall_specs = [WallSpec.model_validate(w) for w in json.loads(str(state["walls_json"]))]
        for attr, prefix, cls_ in (("bodies", "b_", Bodies), ("spheres", "s_", Spheres), ("walls", "w_", Walls),
                                   ("pairs", "p_", Pairs), ("wall_contacts", "c_", WallContacts)):
            setattr(self, attr, cls_(*[state[prefix + f].copy() for f in cls_._fields]))
        self._pending = PendingHistory.from_arrays(state, "pending_")
        self._stale = bool(state["stale"])
        self._records = []
        self._report = None


def _rotate_inverse(quat: np.ndarray, v: np.ndarray) -> np.ndarray:
    w = quat[:, :1]
    q = -quat[:, 1:]
    t = 2.0 * np.cross(q, v)
    return v + w * t + np.cross(q, t)


def _wall_json(spec: WallSpec) -> dict:
    data = spec.model_dump(mode="python")
    g = data["geometry"]
    if g.get("kind") == "mesh":
        g["triangles_m"] = np.asarray(g["triangles_m"]).tolist()
    return json.loads(json.dumps(data, default=lambda o: o.tolist() if hasattr(o, "tolist") else o))
