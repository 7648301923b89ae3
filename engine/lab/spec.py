"""Job specification for virtual laboratory runs: plain data, stored and replayable.

A ``JobSpec`` is what the service queues, what ``demcal run SPEC`` reads and
what designs vary (the design factors are field names of ``MicroParameters``).
"""
from __future__ import annotations

import math
from typing import Annotated, Any, Literal

from pydantic import (BaseModel, ConfigDict, Field, Strict, ValidationInfo, WithJsonSchema, field_validator,
                      model_validator)

from engine.lab.bounds import (CONTACT_STIFFNESS_TYPICAL, DENSEST_SOLID_KG_M3, FRICTION_COEFFICIENT_TYPICAL,
                               MAX_CONTACT_STIFFNESS_N_PER_M, MAX_FRICTION_COEFFICIENT, MAX_PARTICLE_RADIUS_M,
                               MAX_SEED, MIN_PARTICLE_RADIUS_M, NORMAL_STRESS_TYPICAL, PARTICLE_DENSITY_TYPICAL,
                               STIFFEST_SOLID_PA, check_finite_tree)
from engine.lab.registry import BATTERY, JobTestName
from engine.lab.resolution import PRESET_NAMES, ResolutionIn, is_preset
from engine.lab.rigs import Rig
from engine.lab.whole_number import WholeNumber, bounded_whole_number  # noqa: F401  (WholeNumber re-exported)
from engine.particles.description import Particles

# Every model here refuses NaN and infinities (``allow_inf_nan=False``): JSON cannot carry them back,
# so a stored infinity would come back as null and a job "succeed" with a null result.
# Strict types: lax coercion took ``false`` as 0.0 for a number and ``0`` as false for a switch, so a
# client's wrong type ran a job nobody asked for. JSON types map onto these without loss (an integer is a
# valid float); tuples are validated from JSON lists with ``STRICT_PAIR``. The API's input models share it.
STRICT_INPUT = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)
_FINITE = STRICT_INPUT
# A pair of numbers sent as a JSON list: a strict tuple would refuse the list, a lax one take booleans.
STRICT_PAIR = tuple[Annotated[float, Strict()], Annotated[float, Strict()]]


# WholeNumber (engine.lab.whole_number): an integer field that takes 2.0 as 2, refuses true and 2.5.
# Speeds, lengths and counts of a laboratory test: ceilings well above any lab set-up, so that the
# cost model (engine.lab.cost) rather than an overflow decides what is too big.
_MAX_LAB_LENGTH_M = 100.0
_MAX_LAB_SPEED_M_S = 100.0
_MIN_LAB_SPEED_M_S = 1e-6  # 1 um/s, a creep test; slower divides the lab's times into infinities
_MIN_SPEED_FACTOR, _MAX_SPEED_FACTOR = 1e-3, 1e4
_MAX_CCT_CYCLES = 1000
_MAX_DST_STRESSES = 20
# E' read at a few stresses of a compression curve; each is a key of every stored result.
_MAX_CCT_WINDOW_STRESSES = 20
# Contact effects on one material: the registry has a handful; more names than this is not a model.
_MAX_EFFECTS = 16

Fidelity = Literal["screening", "thesis"]


CycleCount = bounded_whole_number(1, _MAX_CCT_CYCLES)

class MicroParameters(BaseModel):
    """DEM micro parameters, SI. Defaults: the thesis's calibrated set (Table 4.9).

    A field's ``Typical`` (engine.lab.bounds) rides in its annotation beside the bound: a value outside is
    accepted with a warning (engine.lab.plausibility.parameter_warnings)."""

    model_config = _FINITE

    particle_density_kg_m3: Annotated[float, PARTICLE_DENSITY_TYPICAL] = Field(2500.0, gt=0, le=DENSEST_SOLID_KG_M3,
                                          description="solid density; at most osmium's")
    particle_stiffness_n_per_m: Annotated[float, CONTACT_STIFFNESS_TYPICAL] = Field(1.72e6, gt=0, le=MAX_CONTACT_STIFFNESS_N_PER_M,
                                              description="kp, PFC-style per-entity normal stiffness")
    wall_stiffness_n_per_m: Annotated[float, CONTACT_STIFFNESS_TYPICAL] = Field(1.0e7, gt=0, le=MAX_CONTACT_STIFFNESS_N_PER_M,
                                          description="kw, PFC-style per-entity normal stiffness")
    # ks/kn of elastic spheres is 2(1 - nu)/(2 - nu): 2/3 to 4/3 over Poisson's ratios -1..0.5; 10 leaves
    # room for linear-model conventions while refusing typos.
    shear_to_normal_stiffness_ratio: float = Field(1.0, gt=0, le=10.0,
                                                   description="ks/kn: each contact's tangential over normal stiffness")
    friction_pp: Annotated[float, FRICTION_COEFFICIENT_TYPICAL] = Field(0.86, ge=0, le=MAX_FRICTION_COEFFICIENT,
                               description="inter-particle Coulomb friction coefficient")
    friction_pw: Annotated[float, FRICTION_COEFFICIENT_TYPICAL] = Field(0.62, ge=0, le=MAX_FRICTION_COEFFICIENT,
                               description="particle-wall Coulomb friction coefficient")
    damping_ratio: float = Field(0.8, ge=0, lt=1, description="critical viscous damping ratio")
    local_damping: float = Field(0.0, ge=0, lt=1, description="Cundall non-viscous damping coefficient")
    particle_radius_m: float | None = Field(
        None, ge=MIN_PARTICLE_RADIUS_M, le=MAX_PARTICLE_RADIUS_M,
        description="screening fidelity only: mono-sized sphere radius (default 0.02 m)",
    )
    clump_aspect_ratio: float = Field(
        1.0, ge=1.0, le=2.0,
        description="screening fidelity only: grains are two-sphere clumps of this length/width "
        "(1 = spheres), each of the solid volume of the sphere it replaces (engine/lab/shape.py); at most 2 "
        "(two spheres that still touch)",
    )
    effects: dict[str, dict[str, Any]] = Field(
        default_factory=dict, max_length=_MAX_EFFECTS,
        description="optional contact effects by registered name (engine.effects.REGISTRY), each with its "
                    "parameters, e.g. {'rolling_epsd2': {'rolling_friction': 0.1}}",
    )

    @field_validator("effects")
    @classmethod
    def _known_effects(cls, effects: dict[str, dict[str, Any]]) -> dict[str, dict[str, Any]]:
        """Each name registered and its parameters valid for that effect, checked when the job is
        submitted: a typo found by the DEM worker hours later is a failed job instead of a 422."""
        from engine.effects import REGISTRY  # the registry imports the effect kernels' modules

        checked: dict[str, dict[str, Any]] = {}
        for name, params in effects.items():
            if name not in REGISTRY:
                raise ValueError(f"unknown contact effect {name!r}; known: {sorted(REGISTRY)}")
            check_finite_tree(params, f"effects.{name}")
            try:
                model = REGISTRY[name].params_model.model_validate(params)
            except ValueError as exc:  # pydantic's ValidationError: name the parameter in the message
                errors = getattr(exc, "errors", None)
                if errors is None:
                    raise
                first = errors(include_url=False)[0]
                where = ".".join(str(p) for p in first.get("loc", ()))
                raise ValueError(f"effects.{name}{'.' + where if where else ''}: {first.get('msg')}") from None
            dumped = model.model_dump()
            check_finite_tree(dumped, f"effects.{name}")
            checked[name] = params
        return checked


class TestOptions(BaseModel):
    """Per-test controls; unset values take the fidelity's defaults."""

    model_config = _FINITE

    dst_normal_stresses_pa: Annotated[list[float] | None, NORMAL_STRESS_TYPICAL] = Field(
        None, min_length=2, max_length=_MAX_DST_STRESSES,
        description="DST normal stresses, Pa: at least two distinct levels (a Mohr-Coulomb line needs two)",
    )
    cct_max_stress_pa: Annotated[float | None, NORMAL_STRESS_TYPICAL] = Field(None, gt=0, le=STIFFEST_SOLID_PA)
    cct_cycles: CycleCount | None = Field(
        None, description="load-unload cycles; each counts in the simulated-time limit")
    cct_window_stresses_pa: list[float] | None = Field(
        None, max_length=_MAX_CCT_WINDOW_STRESSES,
        description="CCT: report the tangent confined modulus E' = d(sigma)/d(strain) at exactly these normal "
        "stresses (Pa; each > 0, strictly increasing, below the CCT maximum stress), keyed by the given floats, "
        "instead of five equal windows from 0 to the peak (docs/lab.md)",
    )
    cct_unload_reload_stresses_pa: list[float] | None = Field(
        None, max_length=_MAX_CCT_WINDOW_STRESSES,
        description="CCT: after its cycles, load once more and at each of these normal stresses (Pa; each > 0, "
        "strictly increasing, below the CCT maximum stress) hold the stress, then unload slowly by a tenth of it: "
        "the unload-reload modulus E_ur = d(sigma)/d(strain) of that small unloading, reported per stress. It grows "
        "with stress as the contacts stiffen (a Hertzian contact's stiffness ~ F^(1/3)), where the loading E' "
        "grows mostly with the contact network (docs/lab.md)",
    )
    speed_factor: float | None = Field(
        None, ge=_MIN_SPEED_FACTOR, le=_MAX_SPEED_FACTOR,
        description="test speed / lab speed for CCT and DST; unset: the fidelity's default (docs/lab.md)",
    )
    max_inertial_number: float = Field(1e-2, gt=0, le=1.0, description="quasi-static below ~1e-3; 1 is flow")
    inertial_number_action: Literal["warn", "refuse"] = Field(
        "warn", description="above max_inertial_number: add a provenance warning, or raise (refuse the run)"
    )
    shear_distance_m: float | None = Field(None, gt=0, le=_MAX_LAB_LENGTH_M,
                                           description="DST shear travel; unset: the fidelity's")
    stop_after_reduced: bool | None = Field(
        None, description="stop each stage once what the reducers read is recorded: the DST shear at the end of the "
        "residual window plus half the smoothing span (at most shear_distance_m), the CCT after its last loading "
        "branch (no reducer reads the last unloading); the reduced values are the same to the bit. Unset: the "
        "fidelity's default (screening true, thesis false; docs/lab.md)",
    )
    dst_speed_by_stress: bool | None = Field(
        None, description="DST: reload and shear each normal stress s above the fidelity's lowest DST stress s0 at "
        "the speed factor's speed times sqrt(s / s0), which keeps the shear's inertial number at the lowest load's "
        "instead of letting it fall as 1/sqrt(s). Unset: the fidelity's default (screening true, thesis false; "
        "docs/lab.md)",
    )
    residual_window_strain: STRICT_PAIR = Field(
        (0.08, 0.10), strict=False, description="DST shear-strain window for residual stresses and dilatancy"
    )
    moving_average_span: WholeNumber = Field(21, ge=1, le=100_001, description="DST smoothing span, points (odd)")
    aor_lift_speed_m_s: float | None = Field(None, ge=_MIN_LAB_SPEED_M_S, le=_MAX_LAB_SPEED_M_S)
    aor_bucket_friction: float | None = Field(None, ge=0, le=MAX_FRICTION_COEFFICIENT,
                                              description="particle-bucket friction (plastic 0.67)")
    aor_floor_friction: float | None = Field(None, ge=0, le=MAX_FRICTION_COEFFICIENT,
                                             description="particle-floor friction (plywood 0.86)")
    anchor_friction: float | None = Field(None, ge=0, le=MAX_FRICTION_COEFFICIENT,
                                          description="particle-anchor friction (bare steel 0.54)")
    anchor_bin_width_m: float | None = Field(None, gt=0, le=_MAX_LAB_LENGTH_M,
                                             description="square bin side; unset: the fidelity's")
    anchor_pull_distance_m: float | None = Field(None, gt=0, le=_MAX_LAB_LENGTH_M,
                                                 description="anchor travel recorded (default 0.1 m)")
    fill_drop_height_m: float | None = Field(
        None, ge=0, le=_MAX_LAB_LENGTH_M,
        description="fill: extra fall height of the rainfall column; unset: the fidelity's (thesis 1.9 m)",
    )
    fill_friction_pp: float | None = Field(
        None, ge=0, le=MAX_FRICTION_COEFFICIENT, description="fill: inter-particle friction while the packing is rained, settled and "
        "levelled (a denser packing at lower friction); parameters.friction_pp is set before the CCT/DST. "
        "Unset: parameters.friction_pp throughout. Shear-box fill only (not the AoR bucket or anchor bin)",
    )
    include_aor: bool = False
    include_anchor: bool = False
    anchor_packing_height_m: float | None = Field(None, gt=0, le=_MAX_LAB_LENGTH_M)
    anchor_pull_speed_m_s: float | None = Field(None, ge=_MIN_LAB_SPEED_M_S, le=_MAX_LAB_SPEED_M_S)

    @field_validator("dst_normal_stresses_pa")
    @classmethod
    def _stress_levels(cls, stresses: list[float] | None) -> list[float] | None:
        """Positive stresses, at least two distinct: one level (or two equal) fits a Mohr-Coulomb line
        exactly or not at all (R^2 1.0 or 1e-16), a friction angle that means nothing."""
        if stresses is None:
            return None
        for stress in stresses:
            if not 0 < stress <= STIFFEST_SOLID_PA:
                raise ValueError(f"normal stress {stress:g} Pa is outside (0, {STIFFEST_SOLID_PA:g}]")
        if len(set(stresses)) < 2:
            raise ValueError("a direct shear test needs at least two distinct normal stresses")
        return stresses

    @field_validator("residual_window_strain")
    @classmethod
    def _window(cls, window: tuple[float, float]) -> tuple[float, float]:
        low, high = window
        if not 0 <= low < high <= 1:
            raise ValueError("need 0 <= lower < upper <= 1 (shear strains)")
        return window

    @field_validator("cct_window_stresses_pa", "cct_unload_reload_stresses_pa")
    @classmethod
    def _window_stresses(cls, value: list[float] | None, info: ValidationInfo) -> list[float] | None:
        # the CCT maximum depends on the fidelity: RunContext.validate checks "below the maximum"
        if value is None:
            return value
        if not value:
            unset = "for five equal windows" if info.field_name == "cct_window_stresses_pa" else "for no unload-reload"
            raise ValueError(f"give at least one stress, or leave the option unset {unset}")
        for s in value:
            if not (math.isfinite(s) and s > 0):
                raise ValueError(f"every stress must be a finite number > 0 Pa, got {s!r}")
        if any(b <= a for a, b in zip(value, value[1:])):
            raise ValueError(f"stresses must be strictly increasing (sorted, no repeats), got {value}")
        return value


# TestOptions kept as the dict that was sent (campaigns store it so), validated as TestOptions, and documented
# with TestOptions' JSON schema: "any object" in the OpenAPI document let schema-valid options be refused.
TestOptionsDict = Annotated[dict[str, Any], WithJsonSchema(TestOptions.model_json_schema())]


class JobSpec(BaseModel):
    """One job. Where it runs: a preset (``fidelity``, or its alias ``resolution`` "thesis"/"screening": a bundled
    rig with bundled particles), or a material's ``particles`` in the ``rig`` its measurements were made in, at
    ``resolution`` "as_measured" or "coarse" (``engine.lab.resolution``). The rig and particles ride in the spec,
    so a stored job replays without the database."""

    model_config = _FINITE

    test: JobTestName = BATTERY
    fidelity: Fidelity = "screening"
    seed: WholeNumber = Field(0, ge=0, le=MAX_SEED)
    parameters: MicroParameters = Field(default_factory=MicroParameters)
    options: TestOptions = Field(default_factory=TestOptions)
    resolution: ResolutionIn | None = Field(
        None, validate_default=True,
        description="'as_measured' or 'coarse' (or {mode, scale_factor | target_particles}): the particles, as "
                    "described or coarse-grained, in the rig; 'thesis' or 'screening': the preset of that name "
                    "(the same as fidelity); unset: the fidelity's preset")
    rig: Rig | None = Field(None, validate_default=True,
                            description="the apparatus (engine.lab.rigs); with resolution as_measured or coarse only")
    particles: Particles | None = Field(
        None, validate_default=True,
        description="the material's particles (engine.particles.description); with resolution as_measured or coarse only")

    @field_validator("resolution")
    @classmethod
    def _preset_alias(cls, resolution: ResolutionIn | None, info: ValidationInfo) -> ResolutionIn | None:
        """A preset name is the fidelity of that name; naming two different presets is refused."""
        parameters = info.data.get("parameters")
        if not is_preset(resolution) and parameters is not None and parameters.particle_radius_m is not None:
            raise ValueError("parameters.particle_radius_m sets the screening preset's spheres; at resolution "
                             f"{_label(resolution)!r} the sizes are the particles' (times the coarse factor): unset it")
        if resolution in PRESET_NAMES and info.data.get("fidelity") not in (None, resolution) \
                and info.data.get("fidelity") != "screening":  # "screening" is the default, not a choice
            raise ValueError(f"resolution {resolution!r} and fidelity {info.data.get('fidelity')!r} name different "
                             "presets; send one")
        return resolution

    @field_validator("rig", "particles")
    @classmethod
    def _with_material_resolution(cls, value, info: ValidationInfo):
        if "resolution" not in info.data:  # the resolution itself was refused: that error says it
            return value
        preset = is_preset(info.data["resolution"])
        if preset and value is not None:
            raise ValueError(f"a preset (fidelity, or resolution 'thesis'/'screening') brings its own {info.field_name}; "
                             f"send resolution 'as_measured' or 'coarse' to run this {info.field_name}")
        if not preset and value is None:
            raise ValueError(f"resolution {_label(info.data['resolution'])!r} builds a material's particles in its "
                             f"rig: send {info.field_name}")
        return value

    @model_validator(mode="after")
    def _alias_sets_the_preset(self) -> "JobSpec":
        # the alias sets the preset: every reader of spec.fidelity (the presets, the stand-in, stored columns)
        # then sees the preset the resolution names
        if self.resolution in PRESET_NAMES:
            self.fidelity = self.resolution
        return self


def _label(resolution) -> str:
    return resolution if isinstance(resolution, str) else resolution.mode


# Fixed micro parameters kept as the dict that was sent, validated as MicroParameters (campaigns), documented
# with MicroParameters' JSON schema for the same reason as TestOptionsDict.
MicroParametersDict = Annotated[dict[str, Any], WithJsonSchema(MicroParameters.model_json_schema())]
