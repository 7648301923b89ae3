"""Plain-data configuration of a simulation (pydantic), so a job can be stored and replayed.

Stiffness convention (PFC): every entity carries a normal stiffness (particle kp, wall kw) and the
contact stiffness is their series combination, kn = k1 k2 / (k1 + k2). Two equal particles therefore
touch with kn = kp / 2; see docs/engine.md for the EDEM / LIGGGHTS translation.
"""
from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator, model_validator

ContactType = Literal["particle-particle", "particle-wall"]


class _Model(BaseModel):
    model_config = ConfigDict(extra="forbid", arbitrary_types_allowed=True)


class MaterialSpec(_Model):
    """A particle (or wall) material. Walls use `friction`/`stiffness` from their WallSpec instead."""

    name: str = "material"
    density_kg_m3: float = Field(2500.0, gt=0)
    normal_stiffness_n_per_m: float = Field(1.72e6, gt=0, description="PFC-style per-entity kp")
    shear_to_normal_stiffness_ratio: float = Field(1.0, ge=0)
    friction: float = Field(0.5, ge=0, description="particle-particle Coulomb coefficient")
    damping_ratio_normal: float = Field(0.8, ge=0, lt=1)
    damping_ratio_shear: float = Field(0.8, ge=0, lt=1, description="0 switches the tangential dashpot off")
    local_damping: float = Field(0.0, ge=0, lt=1, description="Cundall non-viscous damping coefficient")


class EffectSpec(_Model):
    """An optional contact effect (see engine.effects.REGISTRY) switched on for some pairs.

    `materials` lists material-id pairs (particle, other); for particle-wall contacts `other` is the
    wall's material id. None means every pair.
    """

    name: str
    params: dict[str, Any] = Field(default_factory=dict)
    contact_types: list[ContactType] = Field(default_factory=lambda: ["particle-particle", "particle-wall"])
    materials: list[tuple[int, int]] | None = None


class PairOverride(_Model):
    """Per material-pair values that replace the combination rules (min friction, min damping)."""

    material_a: int = Field(ge=0)
    material_b: int = Field(ge=0)
    friction: float | None = Field(None, ge=0)
    damping_ratio_normal: float | None = Field(None, ge=0, lt=1)
    damping_ratio_shear: float | None = Field(None, ge=0, lt=1)


class PlaneGeom(_Model):
    """Infinite one-sided plane: particles live on the side the normal points to."""

    kind: Literal["plane"] = "plane"
    point_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)


class DiskGeom(_Model):
    kind: Literal["disk"] = "disk"
    centre_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    radius_m: float = Field(gt=0)


class RectangleGeom(_Model):
    """Rectangle centred at `centre_m`, spanned by unit `axis_u` (half size a) and `axis_v` (half size b)."""

    kind: Literal["rectangle"] = "rectangle"
    centre_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis_u: tuple[float, float, float] = (1.0, 0.0, 0.0)
    axis_v: tuple[float, float, float] = (0.0, 1.0, 0.0)
    half_size_u_m: float = Field(gt=0)
    half_size_v_m: float = Field(gt=0)


class CylinderGeom(_Model):
    """Cylinder surface of `radius_m` around an axis through `base_m`, from axial 0 to `height_m`."""

    kind: Literal["cylinder"] = "cylinder"
    base_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    radius_m: float = Field(gt=0)
    height_m: float = Field(gt=0)


class ConeGeom(_Model):
    """Cone frustum surface: radius `radius_bottom_m` at axial 0, `radius_top_m` at `height_m`."""

    kind: Literal["cone"] = "cone"
    base_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    radius_bottom_m: float = Field(ge=0)
    radius_top_m: float = Field(ge=0)
    height_m: float = Field(gt=0)


class BoxGeom(_Model):
    """Solid box (e.g. an anchor plate or tube): particles are kept outside it."""

    kind: Literal["box"] = "box"
    centre_m: tuple[float, float, float] = (0.0, 0.0, 0.0)
    half_extents_m: tuple[float, float, float]
    axis_u: tuple[float, float, float] = (1.0, 0.0, 0.0)
    axis_v: tuple[float, float, float] = (0.0, 1.0, 0.0)


class MeshGeom(_Model):
    """Triangle mesh, (n, 3, 3) vertices in metres (e.g. from engine.io.stl.read_stl)."""

    kind: Literal["mesh"] = "mesh"
    triangles_m: Any

    @field_validator("triangles_m")
    @classmethod
    def _tri(cls, value: Any) -> np.ndarray:
        arr = np.asarray(value, dtype=np.float64)
        if arr.ndim != 3 or arr.shape[1:] != (3, 3) or arr.shape[0] == 0:
            raise ValueError("triangles_m must have shape (n, 3, 3) with n >= 1")
        return arr


Geometry = PlaneGeom | DiskGeom | RectangleGeom | CylinderGeom | ConeGeom | BoxGeom | MeshGeom


class ServoSpec(_Model):
    """Hold a normal force (or stress = force / area) that the wall exerts on the particles.

    `axis` is the direction the wall moves to push harder (e.g. (0, 0, -1) for a lid).
    """

    axis: tuple[float, float, float] = (0.0, 0.0, -1.0)
    target_force_n: float | None = Field(None, ge=0)
    target_stress_pa: float | None = Field(None, ge=0)
    area_m2: float | None = Field(None, gt=0)
    max_speed_m_s: float = Field(0.05, gt=0)
    gain_fraction: float = Field(
        0.3, gt=0, le=1, description="fraction of the force error closed per step through the wall contacts' springs "
                                     "and dashpots; stable below about 1 (2 / (1 + c / (k dt + c)))")

    @model_validator(mode="after")
    def _target(self) -> "ServoSpec":
        if (self.target_force_n is None) == (self.target_stress_pa is None):
            raise ValueError("servo: give exactly one of target_force_n or target_stress_pa")
        if self.target_stress_pa is not None and self.area_m2 is None:
            raise ValueError("servo: target_stress_pa needs area_m2")
        return self

    def target_n(self) -> float:
        if self.target_force_n is not None:
            return float(self.target_force_n)
        return float(self.target_stress_pa) * float(self.area_m2)


class WallSpec(_Model):
    name: str
    geometry: Geometry = Field(discriminator="kind")
    normal_stiffness_n_per_m: float = Field(1.0e7, gt=0, description="PFC-style kw")
    friction: float = Field(0.62, ge=0, description="particle-wall Coulomb coefficient")
    material_id: int = Field(0, ge=0, description="row of the materials table used for effects/damping")
    velocity_m_s: tuple[float, float, float] = (0.0, 0.0, 0.0)
    ramp_time_s: float = Field(0.0, ge=0, description="velocity grows linearly from 0 over this time")
    angular_velocity_rad_s: tuple[float, float, float] = Field(
        (0.0, 0.0, 0.0), description="rigid rotation of the wall (e.g. a drum, a tilting plane)")
    rotation_centre_m: tuple[float, float, float] | None = Field(
        None, description="a point on the rotation axis, carried with the wall's translation; None: the wall's "
                          "reference point")
    servo: ServoSpec | None = None


class SimulationConfig(_Model):
    materials: list[MaterialSpec] = Field(default_factory=lambda: [MaterialSpec()], min_length=1)
    pair_overrides: list[PairOverride] = Field(default_factory=list)
    effects: list[EffectSpec] = Field(default_factory=list)
    gravity_m_s2: tuple[float, float, float] = (0.0, 0.0, -9.81)
    timestep_s: float | None = Field(None, gt=0, description="None: safety_factor x critical step")
    safety_factor: float = Field(0.3, gt=0, le=1)
    skin_m: float | None = Field(None, gt=0, description="Verlet skin; None: 0.5 x smallest radius")
    record_every: int = Field(100, ge=1, description="wall force/moment sampling interval, steps")
    threads: int | None = Field(None, ge=1, description="numba threads; None: numba's default")
    serial_below_spheres: int = Field(
        1000, ge=0, description="fewer spheres than this run on one thread (results do not depend on threads)")
    limit_normal_force_to_repulsive: bool = False
    reorder_every_rebuilds: int = Field(
        20, ge=0, description="renumber bodies internally in cell order every this many neighbour rebuilds, for "
                              "memory locality (0: never); public body ids never change")
    kernel_cache_dir: str | None = Field(None, description="where specialised kernels are written")
    compiled_effects: list[str] = Field(
        default_factory=list,
        description="effects compiled into the kernel even where no pair uses them (one kernel for runs that "
                    "toggle effects)")

    @model_validator(mode="after")
    def _check(self) -> "SimulationConfig":
        n = len(self.materials)
        for p in self.pair_overrides:
            if p.material_a >= n or p.material_b >= n:
                raise ValueError(f"pair_overrides: material id out of range (have {n} materials)")
        for e in self.effects:
            for a, b in e.materials or []:
                if a >= n or b >= n:
                    raise ValueError(f"effects[{e.name}].materials: id out of range (have {n} materials)")
        return self
