"""Limits on what may be queued: jobs, every run of a campaign's design, schedules' templates.

Why one check: a limit that counts only the shear test lets ``cct_cycles: 1e9`` through, and a limit checked
only at job submission lets a campaign create a draft whose runs can never be queued. The cost of a spec is
``engine.lab.cost.estimate`` (particles of the largest packing, simulated time of every test from its
procedure's own stop rules), which names the field that lowers each number; the lab's own pre-run checks
raise ``SpecFieldError`` with the field. A refusal is a 422 naming that field, with the limit and the estimate.
"""
from __future__ import annotations

from engine.lab.cost import Cost, estimate
from engine.lab.errors import SpecFieldError
from engine.lab.spec import JobSpec
from service.config import Settings
from service.errors import Invalid


def validate_spec(spec: JobSpec, field_prefix: str = "") -> None:
    """The lab's own pre-run checks (e.g. DST stresses above the CCT maximum), as a 422 at submission
    rather than a failed job later."""
    from engine.lab.context import RunContext

    try:
        RunContext.from_spec(spec).validate()
    except SpecFieldError as exc:
        raise Invalid(exc.message, f"{field_prefix}{exc.field}") from None


def check_limits(spec: JobSpec, settings: Settings, field_prefix: str = "") -> Cost:
    """422 naming the field to change when ``spec`` is invalid for the lab or over a limit."""
    validate_spec(spec, field_prefix)
    cost = estimate(spec)
    if cost.particles > settings.max_particles:
        raise Invalid(
            f"about {cost.particles} particles in the {cost.particles_stage} stage exceeds the limit of "
            f"{settings.max_particles} (raise particle_radius_m, or DEMCAL_MAX_PARTICLES)",
            field_prefix + cost.particles_field)
    if cost.simulated_time_s > settings.max_simulated_time_s:
        stages = ", ".join(f"{k} {v:.0f} s" for k, v in cost.stages_s.items())
        raise Invalid(
            f"up to {cost.simulated_time_s:.0f} s of simulated time ({stages}) exceeds the limit of "
            f"{settings.max_simulated_time_s:.0f} s (raise options.speed_factor, run fewer cycles or stresses, "
            "or DEMCAL_MAX_SIMULATED_TIME_S)",
            field_prefix + cost.time_field)
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


def check_campaign_limits(config, settings: Settings, field_prefix: str = "", target_keys=()) -> None:
    """A campaign (or a schedule's template) is checked at creation for every run of its design, with
    the same model as a job: a draft that could never queue its runs is a 422 now, not a failure on start.
    Each run's job is built as the runner will queue it (``calibration.conditions.run_spec``), with the
    options its targets derive (``target_keys``: the DST loads and E' stresses of the measurements).

    Particle counts and times depend on the micro parameters only through ``particle_radius_m`` (and on the
    options), each monotonically, so the design's runs include the worst case of any point in the factor
    box, including the confirmation run at the optimum. Factors that are not scalar micro parameters
    (e.g. an effect's strength) do not change the cost and are not applied here.
    """
    from engine.lab.spec import MicroParameters
    from calibration.conditions import run_spec
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
    target_keys = list(target_keys)
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
        spec = run_spec(config, natural, 0, target_keys)
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
            derived = [k for k in ("dst_normal_stresses_pa", "cct_window_stresses_pa")
                       if field.endswith(k) and (config.options.get(k) is None) and getattr(spec.options, k)]
            why = " (the stresses of the material's measurements; set options." + derived[0] + \
                " or choose fewer targets)" if derived else ""
            raise Invalid(f"design run at {point}: {exc.message}{why}", where) from None
