"""One cost model for every limit: jobs, every run of a campaign's design, schedules' templates.

Why one model: a limit that counts only the shear test lets ``cct_cycles: 1e9`` through, and a
limit checked only at job submission lets a campaign create a draft whose runs can never be
queued. Here a spec's cost is estimated from the lab's own presets and procedures before anything
is queued:

* particles: the largest packing any stage builds (the shear-box fill, the angle-of-repose bucket,
  the anchor bin), solids volume x the preset's fill margin / mean particle volume;
* simulated time: every stage the spec runs, each at most what its procedure allows. Settling
  phases stop at their ``max_time_s``; a lid stroke stops at half the packing height (``load_to``'s
  ``max_travel_m``) and runs at the lab lid speed x ``speed_factor``; so the CCT counts every cycle,
  the DST every normal stress (reload, stabilise, shear), the angle of repose its lift of up to three
  bucket heights and the anchor its pull. These are ceilings of the simulated time, not guesses of it.

A refusal is a 422 naming the field to change, with the limit and the estimate.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

from engine.lab.presets import Fidelity, ShapeFraction, fidelity
from engine.lab.spec import JobSpec
from service.config import Settings
from service.errors import Invalid

# Settling stops of the procedures (labsim.settle max_time_s): fill.py rains and settles (6 s) and
# settles again after levelling (2 s); repose.py and anchor.py fill (6 s) and level (2 s) the same way;
# repose.py lets the pile come to rest (5 s); dst.py stabilises each normal stress (0.5 s).
FILL_SETTLE_S = 6.0 + 2.0
PILE_REST_S = 5.0
DST_STABILISE_S = 0.5
# repose.py gives up after lifting the bucket three bucket heights.
AOR_LIFT_HEIGHTS = 3.0


@dataclass
class Cost:
    particles: int = 0
    particles_stage: str = ""
    stages_s: dict[str, float] = field(default_factory=dict)

    @property
    def simulated_time_s(self) -> float:
        return sum(self.stages_s.values())

    def packing(self, stage: str, count: int) -> None:
        if count > self.particles:
            self.particles, self.particles_stage = count, stage


def _preset(spec: JobSpec, field_prefix: str) -> Fidelity:
    try:
        return fidelity(spec.fidelity, spec.parameters.particle_radius_m, spec.parameters.clump_aspect_ratio)
    except ValueError as exc:
        field = "clump_aspect_ratio" if spec.parameters.clump_aspect_ratio != 1.0 else "particle_radius_m"
        raise Invalid(str(exc), f"{field_prefix}parameters.{field}") from None


def _count(solid_m3: float, margin: float, shapes: tuple[ShapeFraction, ...]) -> int:
    """Spheres of the packing (what a step costs): bodies from the solids volume, times the spheres of
    each body. A shape with its own template (the elongated screening clumps) counts its template's
    volume and spheres; the others count as one sphere of their mean radius."""
    spheres_per_m3 = 0.0
    for s in shapes:
        if s.template is not None:
            volume, spheres = s.template.volume_m3, s.template.n_spheres
        else:
            volume, spheres = 4.0 / 3.0 * math.pi * (0.5 * (s.radius_min_m + s.radius_max_m)) ** 3, 1
        spheres_per_m3 += s.volume_fraction / volume * spheres
    return int(math.ceil(solid_m3 * margin * spheres_per_m3))


def _tests(spec: JobSpec) -> list[str]:
    if spec.test != "battery":
        return [spec.test]
    return ["fill", "cct", "dst"] + ["aor"] * spec.options.include_aor + ["anchor"] * spec.options.include_anchor


def estimate(spec: JobSpec, field_prefix: str = "") -> Cost:
    """Particles and simulated time (per stage) of ``spec``; see the module docstring."""
    preset, opts = _preset(spec, field_prefix), spec.options
    speed_factor = opts.speed_factor or preset.default_speed_factor
    lid_speed = preset.lab_lid_speed_m_s * speed_factor
    stroke_s = 0.5 * preset.packing_height_m / lid_speed  # one lid stroke, at most
    tests = _tests(spec)
    cost = Cost()
    if {"fill", "cct", "dst"} & set(tests):
        solids = preset.container_area_m2 * preset.packing_height_m * preset.expected_solid_fraction
        cost.packing("fill", _count(solids, preset.fill_margin, preset.shapes))
        cost.stages_s["fill"] = FILL_SETTLE_S
    if "cct" in tests or "dst" in tests:
        cycles = (opts.cct_cycles or preset.cct_cycles) if "cct" in tests else 1  # the DST's precompression
        cost.stages_s["cct"] = cycles * 2 * stroke_s
    if "dst" in tests:
        stresses = len(opts.dst_normal_stresses_pa or preset.dst_normal_stresses_pa)
        shear_speed = preset.lab_shear_speed_m_s * speed_factor
        shear_s = (opts.shear_distance_m or preset.shear_distance_m) / shear_speed
        cost.stages_s["dst"] = stresses * (stroke_s + DST_STABILISE_S + shear_s)
    if "aor" in tests:
        aor = preset.aor
        bucket_h = aor.scale * aor.bucket_height_m
        r0, r1 = aor.scale * aor.bucket_bottom_radius_m, aor.scale * aor.bucket_top_radius_m
        bucket_m3 = math.pi * bucket_h / 3.0 * (r0**2 + r0 * r1 + r1**2)
        cost.packing("aor", _count(bucket_m3 * preset.expected_solid_fraction, preset.fill_margin,
                                   preset.aor_shapes or preset.shapes))
        lift_speed = opts.aor_lift_speed_m_s or aor.lift_speed_m_s
        cost.stages_s["aor"] = FILL_SETTLE_S + AOR_LIFT_HEIGHTS * bucket_h / lift_speed + PILE_REST_S
    if "anchor" in tests:
        a = preset.anchor
        width = opts.anchor_bin_width_m or a.bin_width_m
        height = opts.anchor_packing_height_m or a.packing_height_m
        cost.packing("anchor", _count(width**2 * height * preset.expected_solid_fraction, preset.fill_margin,
                                      preset.shapes))
        speed = opts.anchor_pull_speed_m_s or a.pull_speed_m_s
        cost.stages_s["anchor"] = FILL_SETTLE_S + a.acceleration_time_s + (
            opts.anchor_pull_distance_m or a.pull_distance_m) / speed
    return cost


def estimated_particles(spec: JobSpec) -> int:
    return estimate(spec).particles


def estimated_simulated_time_s(spec: JobSpec) -> float:
    return estimate(spec).simulated_time_s


def _particles_field(spec: JobSpec, stage: str) -> str:
    if stage == "aor":
        return "options.include_aor" if spec.test == "battery" else "test"
    if stage == "anchor":
        return "options.anchor_bin_width_m"
    return "parameters.particle_radius_m" if spec.fidelity == "screening" else "fidelity"


def _time_field(spec: JobSpec, cost: Cost, preset: Fidelity) -> str:
    """The option that shortens the stage that costs most: the user's own count of cycles or stresses
    when it is above the fidelity's, else the speed."""
    stage = max(cost.stages_s, key=cost.stages_s.get)
    opts = spec.options
    if stage == "cct" and opts.cct_cycles is not None and opts.cct_cycles > preset.cct_cycles:
        return "options.cct_cycles"
    if stage == "dst" and opts.dst_normal_stresses_pa is not None and \
            len(opts.dst_normal_stresses_pa) > len(preset.dst_normal_stresses_pa):
        return "options.dst_normal_stresses_pa"
    return {"aor": "options.aor_lift_speed_m_s", "anchor": "options.anchor_pull_speed_m_s"}.get(
        stage, "options.speed_factor")


def validate_spec(spec: JobSpec, field_prefix: str = "") -> None:
    """The lab's own pre-run checks (e.g. DST stresses above the CCT maximum), as a 422 at submission
    rather than a failed job later; the lab's messages start with the field path."""
    import re

    from engine.lab.context import RunContext

    _preset(spec, field_prefix)
    try:
        RunContext.from_spec(spec).validate()
    except ValueError as exc:
        message = str(exc)
        match = re.match(r"((?:options|parameters)\.[a-z_0-9]+)(:?)\s*", message)
        if match is None:
            raise Invalid(message, f"{field_prefix}options") from None
        raise Invalid(message[match.end():] if match.group(2) else message,
                      f"{field_prefix}{match.group(1)}") from None


def check_limits(spec: JobSpec, settings: Settings, field_prefix: str = "") -> Cost:
    """422 naming the field to change when ``spec`` is invalid for the lab or over a limit."""
    validate_spec(spec, field_prefix)
    cost = estimate(spec, field_prefix)
    if cost.particles > settings.max_particles:
        raise Invalid(
            f"about {cost.particles} particles in the {cost.particles_stage} stage exceeds the limit of "
            f"{settings.max_particles} (raise particle_radius_m, or DEMCAL_MAX_PARTICLES)",
            field_prefix + _particles_field(spec, cost.particles_stage))
    if cost.simulated_time_s > settings.max_simulated_time_s:
        stages = ", ".join(f"{k} {v:.0f} s" for k, v in cost.stages_s.items())
        raise Invalid(
            f"up to {cost.simulated_time_s:.0f} s of simulated time ({stages}) exceeds the limit of "
            f"{settings.max_simulated_time_s:.0f} s (raise options.speed_factor, run fewer cycles or stresses, "
            "or DEMCAL_MAX_SIMULATED_TIME_S)",
            field_prefix + _time_field(spec, cost, _preset(spec, field_prefix)))
    return cost


def design_runs(n_factors: int, n_generators: int, replicates: int, centre_runs: int, axial: bool = False) -> int:
    """Runs of a design, computed before it is built: 2^(k-p) x replicates + centre runs (+ 2k axial)."""
    return 2 ** max(0, n_factors - n_generators) * replicates + centre_runs + (2 * n_factors if axial else 0)


def check_design_size(n_factors: int, n_generators: int, replicates: int, centre_runs: int,
                      settings: Settings, field_prefix: str = "", design_prefix: str = "", axial: bool = False) -> int:
    """A design (preview or campaign) larger than ``max_design_runs`` is refused before it is built: one
    15-factor, 10-replicate preview used 2 GB and 20 s and answered 133 MB."""
    runs = design_runs(n_factors, n_generators, replicates, centre_runs, axial)
    if runs > settings.max_design_runs:
        raise Invalid(f"the design has {runs} runs, over the limit of {settings.max_design_runs} "
                      "(use a fractional design, fewer factors or replicates, or DEMCAL_MAX_DESIGN_RUNS)",
                      f"{field_prefix}{design_prefix}replicates" if replicates > 1 else f"{field_prefix}factors")
    return runs


def check_campaign_limits(config, settings: Settings, field_prefix: str = "") -> None:
    """A campaign (or a schedule's template) is checked at creation for every run of its design, with
    the same model as a job: a draft that could never queue its runs is a 422 now, not a failure on start.

    Particle counts and times depend on the micro parameters only through ``particle_radius_m`` (and on the
    options), each monotonically, so the design's runs include the worst case of any point in the factor
    box, including the confirmation run at the optimum. Factors that are not scalar micro parameters
    (e.g. an effect's strength) do not change the cost and are not applied here.
    """
    from engine.lab.spec import MicroParameters, TestOptions
    from calibration.design import build_design
    from calibration.errors import SettingsError
    from service.errors import from_settings_error

    design = config.design
    check_design_size(len(config.factors), len(design.generators or ()), design.replicates, design.centre_runs,
                      settings, field_prefix, "design.", axial=design.axial != "none")
    try:
        built = build_design(config.factors, design, config.seed, field_prefix=f"{field_prefix}design.")
    except SettingsError as exc:
        raise from_settings_error(exc) from exc
    options = TestOptions.model_validate(config.options)
    seen: set[tuple] = set()
    scalar = set(MicroParameters.model_fields) - {"effects"}
    for record in built.records("std"):
        # only scalar micro parameters can change the cost (an effect's strength cannot): the others,
        # such as dotted effect paths, are left to the campaign's own validation
        natural = {f.name: record[f.name] for f in built.factors if f.name in scalar}
        key = tuple(sorted(natural.items()))
        if key in seen:
            continue
        seen.add(key)
        spec = JobSpec(test=config.test, fidelity=config.fidelity, seed=0, options=options,
                       parameters=MicroParameters.model_validate({**config.fixed_parameters, **natural}))
        try:
            check_limits(spec, settings)
        except Invalid as exc:
            point = ", ".join(f"{k}={v:g}" for k, v in natural.items())
            field = str(exc.field)
            parameter = field.split(".", 1)[1] if field.startswith("parameters.") else None
            if parameter in natural:
                index = next(i for i, f in enumerate(config.factors) if f.name == parameter)
                where = f"{field_prefix}factors.{index}.low"
            elif field.startswith("parameters."):
                where = f"{field_prefix}fixed_parameters.{parameter}"
            else:
                where = field_prefix + field
            raise Invalid(f"design run at {point}: {exc.message}", where) from None
