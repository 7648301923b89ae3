"""The neutral material card: a calibrated material as one documented file, the single input of every export.

Why one card: a calibration is done so that a production simulation (the user's own DEM code) can use
it. The card says everything demcal knows of the calibrated material in SI with units: the particles
(solid density, size distribution, shapes as sphere bodies), the contact law and every contact effect
with its parameters, the calibrated parameters with their uncertainty and design range, the rig and
resolution they were calibrated at, the measurements they were calibrated against with the result per
target, and the demcal version that calibrated it. Every export format (``service.export.formats``:
YAML/JSON card, LIGGGHTS include, ...) is a function of this card alone, so a format cannot see
something the card does not document.

The schema is ``MaterialCard`` (versioned by ``card_version``; docs/export.md describes every field).
It is built from plain views (``build_card``: a campaign's report, optimum and configuration, the
material's measurements), not from database rows, so it is the same from the API, the CLI and a
notebook. ``micro_parameters`` reads a card back into the engine's ``MicroParameters`` (import).

Canonical text: ``dump_json`` / ``dump_yaml`` write the validated card in the schema's field order with
Python's shortest round-trip float repr, so a card read and written again is the same bytes.
"""
from __future__ import annotations

import json
from typing import Annotated, Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from engine.effects import REGISTRY
from engine.lab.presets import fidelity as fidelity_preset
from engine.lab.registry import JobTestName
from engine.lab.spec import Fidelity, MicroParameters, TestOptions, WholeNumber
from engine.lab.units import parameter_si_unit

CARD_VERSION = 1
CARD_FORMAT = "demcal material card"

# The MicroParameters of the particles; the rest of its scalar fields are the contact law's.
PARTICLE_FIELDS = ("particle_density_kg_m3", "particle_radius_m", "clump_aspect_ratio")
CONTACT_FIELDS = tuple(n for n in MicroParameters.model_fields if n not in PARTICLE_FIELDS and n != "effects")

CONTACT_LAW = "linear_spring_dashpot_pfc"
CONTACT_LAW_TEXT = (
    "Linear spring-dashpot with Coulomb friction, PFC-style stiffness: every entity carries a normal stiffness "
    "(particles particle_stiffness_n_per_m, walls wall_stiffness_n_per_m) and a contact's normal stiffness is the "
    "two in series, kn = k1 k2 / (k1 + k2) (two equal particles touch with kp / 2); the tangential stiffness is "
    "ks = shear_to_normal_stiffness_ratio x kn; normal and tangential dashpots c = 2 damping_ratio sqrt(k m_eff) "
    "with the pair's effective mass; tangential force capped at friction x normal force (friction_pp between "
    "particles, friction_pw against walls). Effects below replace the normal spring (stage stiffness), add a "
    "normal force (normal_extra) or a rolling torque (rolling).")

# strict like the API's input (engine.lab.spec.STRICT_INPUT): "0.5" or false is not a number
_STRICT = ConfigDict(extra="forbid", allow_inf_nan=False, strict=True)


class Value(BaseModel):
    """A parameter's value in SI with its unit ("1": dimensionless); null where not set (e.g. an optional
    wall modulus, or the screening radius at the thesis fidelity)."""

    model_config = _STRICT

    value: float | None
    unit: str = Field(..., max_length=16)
    description: str = Field("", max_length=2000, description="what the parameter is (informative; ignored on import)")


class Sphere(BaseModel):
    model_config = _STRICT

    centre_m: list[float] = Field(..., min_length=3, max_length=3, description="in the body's principal frame, centre of mass at 0")
    radius_m: float = Field(..., gt=0)


class RadiusDistribution(BaseModel):
    """The distribution of a shape's sphere radius: constant, Gaussian truncated to [min, max] (mean and sd of
    the Gaussian before truncation), uniform, or "sampled" (a sieve curve or discrete sizes, stated in full in
    ``rig.material_particles``; mean and sd here by number, of 65,536 radii drawn at seed 0)."""

    model_config = _STRICT

    kind: Literal["constant", "truncated_gaussian", "uniform", "sampled"]
    radius_min_m: float = Field(..., gt=0)
    radius_max_m: float = Field(..., gt=0)
    mean_m: float = Field(..., gt=0)
    sd_m: float = Field(..., ge=0)


class Shape(BaseModel):
    """One grain shape of the mix: rigid sphere bodies, and their share of the solid volume."""

    model_config = _STRICT

    shape: str = Field(..., max_length=64)
    volume_fraction: float = Field(..., ge=0, le=1)
    radius_distribution: RadiusDistribution
    body: str = Field(..., max_length=2000, description="how a body is built from its sphere radius")
    reference_spheres: list[Sphere] = Field(..., min_length=1, max_length=1000,
                                            description="the body at the distribution's largest sphere radius")
    reference_volume_m3: float = Field(..., gt=0)


class Particles(BaseModel):
    model_config = _STRICT

    parameters: dict[str, Value] = Field(..., max_length=32,
                                         description=f"the particle micro parameters: {', '.join(PARTICLE_FIELDS)}")
    shapes: list[Shape] = Field(..., min_length=1, max_length=32,
                                description="follow from the rig and the parameters (checked on import)")


class EffectCard(BaseModel):
    model_config = _STRICT

    stage: str = Field(..., max_length=32)
    description: str = Field("", max_length=10_000)
    parameters: dict[str, Value] = Field(..., max_length=16)


class Contact(BaseModel):
    model_config = _STRICT

    law: Literal["linear_spring_dashpot_pfc"]
    description: str = Field("", max_length=10_000)
    parameters: dict[str, Value] = Field(..., max_length=32)
    effects: dict[str, EffectCard] = Field(default_factory=dict, max_length=16)


class Rig(BaseModel):
    """The virtual laboratory the parameters were calibrated in: a fidelity preset, or the material's own
    particles (``material_particles``) at a ``resolution`` in the apparatus its measurements were made in
    (``rig_record``); the test battery and its options; and the resolution (grain size against the container)."""

    model_config = _STRICT

    fidelity: Fidelity | None = Field(None, description="a preset's set-up ('thesis', 'screening'); null at a "
                                                        "material resolution")
    resolution: Literal["as_measured", "coarse"] | None = Field(
        None, description="a material resolution: the material's particles as described, or coarse-grained")
    scale_factor: float = Field(1.0, gt=0, description="particle sizes simulated over the material's (coarse)")
    rig_record: dict[str, Any] | None = Field(None, description="at a material resolution: the apparatus, as "
                                                                "engine.lab.rigs.Rig records it")
    material_particles: dict[str, Any] | None = Field(
        None, description="at a material resolution: the material's own particles (engine.particles.description); "
                          "particles.shapes above are these at the scale factor")
    test: JobTestName
    options: dict[str, Any] = Field(default_factory=dict, max_length=64,
                                    description="the campaign's lab options (TestOptions)")
    container_radius_m: float
    container_height_m: float
    smallest_sphere_radius_m: float
    largest_sphere_radius_m: float
    container_diameter_in_largest_grains: float = Field(
        ..., description="container diameter / largest grain's bounding diameter: the rig's resolution")

    @field_validator("options")
    @classmethod
    def _options(cls, options: dict[str, Any]) -> dict[str, Any]:
        TestOptions.model_validate(options)
        return options

    @field_validator("rig_record")
    @classmethod
    def _rig_record(cls, record: dict[str, Any] | None) -> dict[str, Any] | None:
        from engine.lab.rigs import Rig as RigRecord

        if record is not None:
            RigRecord.model_validate(record)
        return record

    @field_validator("material_particles")
    @classmethod
    def _material_particles(cls, particles: dict[str, Any] | None) -> dict[str, Any] | None:
        from engine.particles.description import Particles as ParticlesDescription

        if particles is not None:
            ParticlesDescription.model_validate(particles)
        return particles

    @model_validator(mode="after")
    def _one_set_up(self):
        material = (self.resolution, self.rig_record, self.material_particles)
        if self.fidelity is not None and any(x is not None for x in material):
            raise ValueError("a preset (fidelity) brings its own rig and particles: give fidelity, or resolution "
                             "with rig_record and material_particles, not both")
        if self.fidelity is None and any(x is None for x in material):
            raise ValueError("give fidelity (a preset), or resolution with rig_record and material_particles")
        if self.resolution == "as_measured" and self.scale_factor != 1.0:
            raise ValueError("scale_factor: as measured is 1; a coarse resolution has its factor")
        return self


class CalibratedParameter(BaseModel):
    model_config = _STRICT

    name: str = Field(..., max_length=128, description="a micro parameter or effects.<effect>.<parameter>")
    value: float
    unit: str = Field(..., max_length=16)
    standard_uncertainty: float | None = Field(
        None, description="of the estimate: the report's intervals (every noise term, widened when the fit fails; "
                          "calibration.intervals), else the optimiser's from the fitted response surfaces")
    interval_95: list[float] | None = Field(None, min_length=2, max_length=2,
                                            description="95 % interval (low, high), cut at the design range")
    design_range: list[float] = Field(..., min_length=2, max_length=2, description="low, high of the design factor")


class Calibration(BaseModel):
    """Where the values came from: the campaign, its iteration and verdict, what was calibrated."""

    model_config = _STRICT

    campaign_id: WholeNumber | None
    campaign_name: str = Field(..., max_length=200)
    iteration: WholeNumber = Field(..., ge=1)
    evaluator: str = Field(..., max_length=64)
    verdict: str | None = Field(None, max_length=200)
    meaning: str | None = Field(None, max_length=10_000)
    confirmation_seeds: list[WholeNumber] = Field(default_factory=list, max_length=1000)
    parameters: list[CalibratedParameter] = Field(default_factory=list, max_length=64)
    trades: list[Annotated[str, Field(max_length=1000)]] = Field(
        default_factory=list, max_length=64,
        description="parameter pairs the measurements fix only in combination (their correlation reaches 0.9)")
    fixed_by_campaign: list[Annotated[str, Field(max_length=128)]] = Field(default_factory=list, max_length=64,
                                         description="parameters the campaign fixed; the others are demcal's defaults")


class TargetResult(BaseModel):
    """The calibrated model against one measurement (calibration.report), in the measurement's unit."""

    model_config = _STRICT

    status: str = Field(..., max_length=32)
    measured_uncertainty: float | None = Field(None, description="the standard uncertainty the calibration weighed it with")
    uncertainty_assumed: bool | None = Field(None, description="true: the campaign's default relative uncertainty, not the data's")
    confirmed: float | None = None
    predicted: float | None = None
    prediction_interval: list[float | None] | None = Field(None, min_length=2, max_length=2)
    standardised_residual: float | None = None
    reachability: float | None = None


class MeasurementCard(BaseModel):
    """A measurement the calibration used, as stored (SI), with the calibrated model's result."""

    model_config = _STRICT

    test: str = Field(..., max_length=32)
    quantity: str = Field(..., max_length=64)
    condition: dict[str, float] = Field(default_factory=dict, max_length=8)
    unit: str = Field(..., max_length=16)
    values: list[float] = Field(..., min_length=1, max_length=1000)
    reported_replicates: WholeNumber | None = None
    stated_uncertainty: float | None = None
    source: str = Field("", max_length=10_000)
    mean: float | None = Field(None, description="derived from values (informative)")
    standard_uncertainty: float | None = Field(None, description="derived (informative)")
    result: TargetResult | None = None


class MaterialInfo(BaseModel):
    model_config = _STRICT

    name: str = Field(..., min_length=1, max_length=200)
    description: str = Field("", max_length=10_000)
    source: str = Field("", max_length=10_000)


class MaterialCard(BaseModel):
    """A calibrated material, version ``card_version`` (docs/export.md)."""

    model_config = _STRICT

    card_version: Literal[1] = CARD_VERSION
    format: Literal["demcal material card"] = CARD_FORMAT
    demcal_version: str = Field(..., max_length=64, description="the demcal that calibrated the material")
    material: MaterialInfo
    particles: Particles
    contact: Contact
    rig: Rig
    calibration: Calibration | None = Field(..., description="null: a card of given parameters (parameters_card), "
                                                             "not of a calibration")
    measurements: list[MeasurementCard] = Field(default_factory=list, max_length=1000)


class CardError(ValueError):
    """A card that does not describe a material demcal can build; ``field`` is the dotted path."""

    def __init__(self, field: str, message: str):
        super().__init__(message)
        self.field = field


# -- building --------------------------------------------------------------------------------------

def _describe(model: type[BaseModel], name: str) -> str:
    return model.model_fields[name].description or ""


def _value(model: type[BaseModel], name: str, value: Any) -> dict[str, Any]:
    return {"value": None if value is None else float(value), "unit": parameter_si_unit(name),
            "description": _describe(model, name)}


def _effect_cards(effects: dict[str, dict[str, Any]]) -> dict[str, Any]:
    out = {}
    for name, params in effects.items():
        effect = REGISTRY[name]
        full = effect.params_model.model_validate(params).model_dump()  # defaults filled in: all of them stated
        out[name] = {"stage": effect.stage, "description": (effect.doc or "").strip(),
                     "parameters": {p: _value(effect.params_model, p, v) for p, v in full.items()}}
    return out


_BODIES = {
    "sphere": "one sphere of the drawn radius",
    "pyramid": "four equal touching spheres of the drawn radius r on the vertices of a regular tetrahedron of edge 2 r",
    "double_clump": "two spheres, each radius drawn independently, centres r1 + r2 apart (thesis Eq. 4.10, C = 1)",
}


def _distribution(s) -> dict[str, Any]:
    """A shape's radius distribution as the card states it (see RadiusDistribution). A range without a size form
    is the fill's truncated Gaussian at its defaults (engine.particles.distributions.TruncatedGaussian)."""
    from engine.particles import distributions as dist

    r_min, r_max = float(s.radius_min_m), float(s.radius_max_m)
    if r_min == r_max:
        return {"kind": "constant", "radius_min_m": r_min, "radius_max_m": r_max, "mean_m": r_min, "sd_m": 0.0}
    size = s.size if s.size is not None and not isinstance(s.size, dist.ConstantSize) else \
        dist.TruncatedGaussian(r_min, r_max)
    kind, mean, sd = dist.described(size)
    return {"kind": kind, "radius_min_m": r_min, "radius_max_m": r_max, "mean_m": float(mean), "sd_m": float(sd)}


def _shapes(preset) -> list[dict[str, Any]]:
    """The fill's shape mix (engine.lab.procedures.fill.shape_mix builds the same) as sphere bodies."""
    out = []
    for s in preset.shapes:
        r_max = float(s.radius_max_m)
        if s.template is not None and s.size is not None:  # a material's custom clump, scaled to each drawn size
            distribution = _distribution(s)
            body = "this body scaled so that its largest sphere has the drawn radius"
            template = s.template.scaled(r_max / float(max(s.template.sphere_radii_m)))
        elif s.template is not None:
            body, template = "this body as given (not scaled)", s.template
            distribution = {"kind": "constant", "radius_min_m": r_max, "radius_max_m": r_max, "mean_m": r_max,
                            "sd_m": 0.0}
        else:
            distribution = _distribution(s)
            if s.shape not in _BODIES:
                raise ValueError(f"shape {s.shape!r} has no card description")
            body, template = _BODIES[s.shape], _shape_template(s.shape, r_max)
        out.append({"shape": s.shape, "volume_fraction": float(s.volume_fraction),
                    "radius_distribution": distribution, "body": body,
                    "reference_spheres": [{"centre_m": [float(c) for c in centre], "radius_m": float(r)}
                                          for centre, r in zip(template.sphere_offsets_m, template.sphere_radii_m)],
                    "reference_volume_m3": float(template.volume_m3)})
    return out


def set_up(where: dict[str, Any], params: MicroParameters):
    """The lab set-up (engine.lab.setup.Fidelity) a card's rig section names: its preset, or the material's
    particles at its resolution in its rig record, built by the rule every job uses (engine.lab.resolution)."""
    if where.get("fidelity") is not None:
        return fidelity_preset(where["fidelity"], params.particle_radius_m, params.clump_aspect_ratio)
    from engine.lab.resolution import setup_for
    from engine.lab.spec import JobSpec

    resolution = where["resolution"] if where["resolution"] == "as_measured" else \
        {"mode": "coarse", "scale_factor": where["scale_factor"]}
    spec = JobSpec.model_validate({"test": where["test"], "resolution": resolution, "rig": where["rig_record"],
                                   "particles": where["material_particles"],
                                   "parameters": params.model_dump(mode="json")})
    return setup_for(spec)


def _rig(where: dict[str, Any], params: MicroParameters) -> dict[str, Any]:
    preset = set_up(where, params)
    # the largest grain: each shape's body at its largest sphere radius
    largest = max(2.0 * (s.template if s.template is not None else
                         _shape_template(s.shape, float(s.radius_max_m))).bounding_radius_m for s in preset.shapes)
    material = where.get("fidelity") is None
    return {"fidelity": where.get("fidelity"), "resolution": where.get("resolution") if material else None,
            "scale_factor": float(preset.scale_factor) if material else 1.0,
            "rig_record": where.get("rig_record") if material else None,
            "material_particles": where.get("material_particles") if material else None,
            "test": where["test"], "options": dict(where.get("options") or {}),
            "container_radius_m": float(preset.container_radius_m),
            "container_height_m": float(preset.container_height_m),
            "smallest_sphere_radius_m": float(min(s.radius_min_m for s in preset.shapes)),
            "largest_sphere_radius_m": float(max(s.radius_max_m for s in preset.shapes)),
            "container_diameter_in_largest_grains": float(preset.container_diameter_m / largest)}


def _shape_template(shape: str, radius_m: float):
    from engine.particles import templates as tpl

    return {"sphere": tpl.sphere, "pyramid": tpl.pyramid,
            "double_clump": lambda r: tpl.double_clump(r, r)}[shape](radius_m)


def physics_sections(params: MicroParameters, where: dict[str, Any]) -> dict[str, Any]:
    """The particles, contact and rig sections: everything that follows from the micro parameters and the rig
    section ``where`` (fidelity, or resolution with scale_factor, rig_record and material_particles; test;
    options)."""
    dumped = params.model_dump()
    return {
        "particles": {"parameters": {n: _value(MicroParameters, n, dumped[n]) for n in PARTICLE_FIELDS},
                      "shapes": _shapes(set_up(where, params))},
        "contact": {"law": CONTACT_LAW, "description": CONTACT_LAW_TEXT,
                    "parameters": {n: _value(MicroParameters, n, dumped[n]) for n in CONTACT_FIELDS},
                    "effects": _effect_cards(dumped["effects"])},
        "rig": _rig(where, params),
    }


def rig_where(rig: dict[str, Any]) -> dict[str, Any]:
    """What ``physics_sections`` needs of a card's rig section (the rest of it follows from these)."""
    return {k: rig.get(k) for k in ("fidelity", "resolution", "scale_factor", "rig_record", "material_particles",
                                    "test", "options")}


def _target_result(row: dict[str, Any] | None) -> dict[str, Any] | None:
    if row is None:
        return None
    interval = row.get("prediction_interval")
    return {"status": row["status"], "measured_uncertainty": row.get("measured_uncertainty"),
            "uncertainty_assumed": row.get("uncertainty_assumed"), "confirmed": row.get("confirmed"), "predicted": row.get("predicted"),
            "prediction_interval": list(interval) if interval is not None else None,
            "standardised_residual": row.get("standardised_residual"), "reachability": row.get("reachability")}


def measurement_card(m: dict[str, Any], result: dict[str, Any] | None) -> dict[str, Any]:
    """A stored measurement (service.materials.store.measurement_dict) with its result row."""
    return {"test": m["test"], "quantity": m["quantity"], "condition": dict(m["condition"]), "unit": m["unit"],
            "values": list(m["values"]), "reported_replicates": m.get("reported_replicates"),
            "stated_uncertainty": m.get("stated_uncertainty"), "source": m.get("source") or "",
            "mean": m.get("mean"), "standard_uncertainty": m.get("standard_uncertainty"),
            "result": _target_result(result)}


def build_card(*, material: dict[str, Any], measurements: list[dict[str, Any]], campaign: dict[str, Any],
               iteration: int, report: dict[str, Any], parameter_std: dict[str, float] | None,
               demcal_version: str) -> dict[str, Any]:
    """The card of one calibrated iteration, as a validated dict in the schema's order.

    ``campaign``: id, name, and the iteration's evaluator, set-up (fidelity, or resolution with scale_factor,
    rig_record and material_particles), test, options and factors (each
    iteration may have its own: an added effect, a narrowed range); ``report``: the iteration's report
    (calibration.report.build_report); ``measurements``: the material's stored measurements
    (measurement_dict), of which the report's targets are kept, in the report's order.
    """
    from calibration import parameters as factor_paths

    params = MicroParameters.model_validate(factor_paths.apply(report.get("fixed_parameters") or {},
                                                               report.get("optimum") or {}))
    ranges = {f["name"]: (float(f["low"]), float(f["high"])) for f in campaign.get("factors") or []}
    intervals = (report.get("intervals") or {}).get("parameters") or {}

    def interval(name):
        row = intervals.get(name) or {}
        return None if row.get("low") is None else [float(row["low"]), float(row["high"])]

    calibrated = [{"name": name, "value": float(value), "unit": parameter_si_unit(name.split(".")[-1]),
                   "standard_uncertainty": (intervals.get(name) or {}).get("sd", (parameter_std or {}).get(name)),
                   "interval_95": interval(name),
                   "design_range": list(ranges.get(name, (float(value), float(value))))}
                  for name, value in (report.get("optimum") or {}).items()]
    trades = [t["message"] for t in (report.get("intervals") or {}).get("trades") or []]
    by_id = {m["id"]: m for m in measurements}
    used = [(by_id[row["measurement_id"]], row) for row in report.get("targets", [])
            if row.get("measurement_id") in by_id]
    card = {
        "card_version": CARD_VERSION, "format": CARD_FORMAT, "demcal_version": demcal_version,
        "material": {"name": material["name"], "description": material.get("description") or "",
                     "source": material.get("source") or ""},
        **physics_sections(params, rig_where(campaign)),
        "calibration": {"campaign_id": campaign["id"], "campaign_name": campaign["name"], "iteration": iteration,
                        "evaluator": campaign["evaluator"], "verdict": report.get("verdict"),
                        "meaning": report.get("meaning"),
                        "confirmation_seeds": list(report.get("confirmation_seeds") or []),
                        "parameters": calibrated, "trades": trades,
                        "fixed_by_campaign": sorted(report.get("fixed_parameters") or {})},
        "measurements": [measurement_card(m, row) for m, row in used],
    }
    return canonical(card)


def parameters_card(params: MicroParameters, *, fidelity: str = "screening", test: str = "battery",
                    options: dict[str, Any] | None = None, name: str = "given parameters",
                    demcal_version: str = "unknown") -> dict[str, Any]:
    """A card of given micro parameters, without a calibration behind them (``calibration`` null, no
    measurements): what an export format's tests and a cross-engine check at chosen parameters start from."""
    return canonical({
        "card_version": CARD_VERSION, "format": CARD_FORMAT, "demcal_version": demcal_version,
        "material": {"name": name, "description": "", "source": ""},
        **physics_sections(params, {"fidelity": fidelity, "test": test, "options": dict(options or {})}),
        "calibration": None, "measurements": [],
    })


# -- reading ---------------------------------------------------------------------------------------

def validate(data: Any) -> MaterialCard:
    """The card as the schema reads it; CardError naming the first bad field."""
    try:
        return MaterialCard.model_validate(data)
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        where = ".".join(str(p) for p in first.get("loc", ())) or "card"
        raise CardError(where, f"{where}: {first.get('msg')}") from None


def canonical(data: Any) -> dict[str, Any]:
    """The card validated and dumped in the schema's order (what is stored, served and compared)."""
    return validate(data).model_dump(mode="json")


def _read_values(section: dict[str, Value], names, where: str) -> dict[str, Any]:
    out = {}
    for name, entry in section.items():
        if name not in names:
            raise CardError(f"{where}.{name}", f"{where}.{name}: not a parameter of this section; known: {sorted(names)}")
        unit = parameter_si_unit(name)
        if entry.unit != unit:
            raise CardError(f"{where}.{name}.unit", f"{where}.{name}.unit: {entry.unit!r}; this parameter is stated in "
                                                    f"SI, {unit!r}")
        if entry.value is not None:
            out[name] = entry.value
    return out


def micro_parameters(card: MaterialCard) -> MicroParameters:
    """The engine's parameters the card states; CardError naming the field where it cannot be built, or
    where its particles or rig are not what those parameters give (the particles follow from the rig and
    the particle parameters: edit those, not the shapes)."""
    values = {**_read_values(card.particles.parameters, PARTICLE_FIELDS, "particles.parameters"),
              **_read_values(card.contact.parameters, CONTACT_FIELDS, "contact.parameters")}
    effects = {}
    for name, effect in card.contact.effects.items():
        if name not in REGISTRY:
            raise CardError(f"contact.effects.{name}", f"contact.effects.{name}: unknown contact effect; known: "
                                                       f"{sorted(REGISTRY)}")
        where = f"contact.effects.{name}.parameters"
        effects[name] = _read_values(effect.parameters, tuple(REGISTRY[name].params_model.model_fields), where)
        try:
            REGISTRY[name].params_model.model_validate(effects[name])
        except ValidationError as exc:
            first = exc.errors(include_url=False)[0]
            param = ".".join(str(p) for p in first.get("loc", ()))
            field = f"{where}.{param}.value" if param else where
            raise CardError(field, f"{field}: {first.get('msg')}") from None
    try:
        params = MicroParameters.model_validate({**values, "effects": effects})
    except ValidationError as exc:
        first = exc.errors(include_url=False)[0]
        loc = [str(p) for p in first.get("loc", ())]
        section = "particles.parameters" if loc and loc[0] in PARTICLE_FIELDS else "contact.parameters"
        if loc and loc[0] == "effects":
            section, loc = "contact.effects", loc[1:]
        where = ".".join([section, *loc])
        raise CardError(where, f"{where}: {first.get('msg')}") from None
    where = card.rig.fidelity is not None and "rig.fidelity" or "rig.resolution"
    try:
        derived = physics_sections(params, rig_where(card.rig.model_dump(mode="json")))
    except ValidationError as exc:  # the job spec the set-up is built from, e.g. a radius at a material resolution
        first = exc.errors(include_url=False)[0]
        raise CardError(where, f"{where}: {first.get('msg')}") from None
    except ValueError as exc:  # e.g. a screening radius at the thesis fidelity
        raise CardError(where, f"{where}: {exc}") from None
    given = card.model_dump(mode="json")
    for section, key in (("particles", "shapes"), ("rig", None)):
        mine = derived[section] if key is None else derived[section][key]
        theirs = given[section] if key is None else given[section][key]
        if canonical_json(mine) != canonical_json(theirs):
            where = section if key is None else f"{section}.{key}"
            built = card.rig.fidelity or f"{card.rig.resolution} x {card.rig.scale_factor:g}"
            raise CardError(where, f"{where}: not what the rig ({built}) builds with these particle parameters; the "
                                   "particles follow from the rig and particles.parameters (edit those)")
    return params


def canonical_json(data: Any) -> str:
    return json.dumps(data, sort_keys=True)


# -- text ------------------------------------------------------------------------------------------

def dump_json(card: dict[str, Any]) -> str:
    return json.dumps(canonical(card), indent=1, ensure_ascii=False, allow_nan=False) + "\n"


def dump_yaml(card: dict[str, Any]) -> str:
    header = (f"# {CARD_FORMAT}, version {CARD_VERSION}: every value in SI with its unit (docs/export.md).\n"
              "# Import: demcal material import-card FILE\n")
    return header + yaml.safe_dump(canonical(card), sort_keys=False, allow_unicode=True, width=100)


def load_text(text: str) -> Any:
    """JSON or YAML text as data (JSON is YAML); CardError when it is neither."""
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise CardError("card", f"card: not YAML or JSON: {str(exc).splitlines()[0]}") from None
