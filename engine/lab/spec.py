"""Job specification for virtual laboratory runs: plain data, stored and replayable.

A ``JobSpec`` is what the service queues, what ``demcal run SPEC`` reads and
what designs vary (the design factors are field names of ``MicroParameters``).
"""
from __future__ import annotations

import math
from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, field_validator

TestName = Literal["fill", "cct", "dst", "aor", "anchor", "battery"]
Fidelity = Literal["screening", "thesis"]


class MicroParameters(BaseModel):
    """DEM micro parameters, SI. Defaults: the thesis's calibrated set (Table 4.9)."""

    model_config = ConfigDict(extra="forbid")

    particle_density_kg_m3: float = Field(2500.0, gt=0)
    particle_stiffness_n_per_m: float = Field(1.72e6, gt=0, description="kp, PFC-style per-entity normal stiffness")
    wall_stiffness_n_per_m: float = Field(1.0e7, gt=0, description="kw, PFC-style per-entity normal stiffness")
    shear_to_normal_stiffness_ratio: float = Field(1.0, gt=0)
    friction_pp: float = Field(0.86, ge=0, description="inter-particle Coulomb friction coefficient")
    friction_pw: float = Field(0.62, ge=0, description="particle-wall Coulomb friction coefficient")
    damping_ratio: float = Field(0.8, ge=0, lt=1, description="critical viscous damping ratio")
    local_damping: float = Field(0.0, ge=0, lt=1)
    particle_radius_m: float | None = Field(
        None, gt=0, description="screening fidelity only: mono-sized sphere radius (default 0.02 m)"
    )
    clump_aspect_ratio: float = Field(
        1.0, ge=1.0, le=2.0,
        description="screening fidelity only: grains are two-sphere clumps of this length/width "
        "(1 = spheres), each of the solid volume of the sphere it replaces (engine/lab/shape.py); the DEM "
        "lab builds up to 2 (two touching spheres), the range to 3 is for stand-in evaluators",
    )
    effects: dict[str, dict[str, Any]] = Field(
        default_factory=dict,
        description="optional contact effects by registered name, e.g. {'rolling_epsd2': {'rolling_friction': 0.1}}",
    )


class TestOptions(BaseModel):
    """Per-test controls; unset values take the fidelity's defaults."""

    model_config = ConfigDict(extra="forbid")

    dst_normal_stresses_pa: list[float] | None = None
    cct_max_stress_pa: float | None = None
    cct_cycles: int | None = Field(None, ge=1)
    cct_window_stresses_pa: list[float] | None = Field(
        None,
        description="CCT: report the tangent confined modulus E' = d(sigma)/d(strain) at exactly these normal "
        "stresses (Pa; each > 0, strictly increasing, below the CCT maximum stress), keyed by the given floats, "
        "instead of five equal windows from 0 to the peak (docs/lab.md)",
    )
    speed_factor: float | None = Field(
        None, gt=0,
        description="test speed / lab speed for CCT and DST; unset: the fidelity's default (docs/lab.md)",
    )
    max_inertial_number: float = Field(1e-2, gt=0)
    inertial_number_action: Literal["warn", "refuse"] = Field(
        "warn", description="above max_inertial_number: add a provenance warning, or raise (refuse the run)"
    )
    shear_distance_m: float | None = Field(None, gt=0, description="DST shear travel; unset: the fidelity's")
    residual_window_strain: tuple[float, float] = Field(
        (0.08, 0.10), description="DST shear-strain window for residual stresses and dilatancy"
    )
    moving_average_span: int = Field(21, ge=1, description="DST smoothing span, points (odd)")
    aor_lift_speed_m_s: float | None = Field(None, gt=0)
    aor_bucket_friction: float | None = Field(None, ge=0, description="particle-bucket friction (plastic 0.67)")
    aor_floor_friction: float | None = Field(None, ge=0, description="particle-floor friction (plywood 0.86)")
    anchor_friction: float | None = Field(None, ge=0, description="particle-anchor friction (bare steel 0.54)")
    anchor_bin_width_m: float | None = Field(None, gt=0, description="square bin side; unset: the fidelity's")
    anchor_pull_distance_m: float | None = Field(None, gt=0, description="anchor travel recorded (default 0.1 m)")
    fill_drop_height_m: float | None = Field(
        None, ge=0, description="fill: extra fall height of the rainfall column; unset: the fidelity's (thesis 1.9 m)"
    )
    fill_friction_pp: float | None = Field(
        None, ge=0, description="fill: inter-particle friction while the packing is rained, settled and "
        "levelled (a denser packing at lower friction); parameters.friction_pp is set before the CCT/DST. "
        "Unset: parameters.friction_pp throughout. Shear-box fill only (not the AoR bucket or anchor bin)",
    )
    include_aor: bool = False
    include_anchor: bool = False
    anchor_packing_height_m: float | None = None
    anchor_pull_speed_m_s: float | None = None

    @field_validator("cct_window_stresses_pa")
    @classmethod
    def _window_stresses(cls, value: list[float] | None) -> list[float] | None:
        # the CCT maximum depends on the fidelity: RunContext.validate checks "below the maximum"
        if value is None:
            return value
        if not value:
            raise ValueError("give at least one stress, or leave the option unset for five equal windows")
        for s in value:
            if not (math.isfinite(s) and s > 0):
                raise ValueError(f"every stress must be a finite number > 0 Pa, got {s!r}")
        if any(b <= a for a, b in zip(value, value[1:])):
            raise ValueError(f"stresses must be strictly increasing (sorted, no repeats), got {value}")
        return value


class JobSpec(BaseModel):
    model_config = ConfigDict(extra="forbid")

    test: TestName = "battery"
    fidelity: Fidelity = "screening"
    seed: int = Field(0, ge=0)
    parameters: MicroParameters = Field(default_factory=MicroParameters)
    options: TestOptions = Field(default_factory=TestOptions)
