"""The calibration loop's settings as users send them: factors, design, priors, constraints and the
rules of the loop. Validated once; a campaign stores them as JSON and the runner re-reads them."""
from __future__ import annotations

from typing import Annotated, Any, Literal

from pydantic import BaseModel, Field, ValidationInfo, field_validator, model_validator

from calibration import parameters as factor_paths
from calibration.discrepancy import Discrepancy
from doe.constraints import MAX_CONSTRAINT_CHARS, parse_constraint
from doe.factors import DoeError
from engine.lab.registry import BATTERY, JobTestName
from engine.lab.resolution import PRESET_NAMES, ResolutionIn, is_preset
from engine.lab.rigs import Rig
from engine.lab.spec import STRICT_INPUT, MicroParameters, MicroParametersDict, TestOptions, TestOptionsDict, WholeNumber
from engine.particles.description import Particles

# Every schema here refuses NaN and infinities: stored, they come back as null and the campaign fails later
# with an empty reason.
_FINITE = STRICT_INPUT  # no NaN, no infinities, no booleans for numbers (engine.lab.spec)

# Free text (a prior's source) is stored with the campaign and returned by every listing: a 40 MB source was
# accepted and every GET /campaigns then answered 42 MB. A reference fits in this.
MAX_SOURCE_CHARS = 10_000
# A generator ('D=ABC', or a factor's name, up to 64 characters, for D) names at most the 15 factors of a preview.
MAX_GENERATOR_CHARS = 200
# automatic mode: iterations at most, the first included (a continued loop too: machine.extended)
MAX_ITERATIONS = 10

# Design factors must be scalar MicroParameters fields (the lab varies those).
FACTOR_NAMES = tuple(
    name for name, info in MicroParameters.model_fields.items() if name not in ("effects",)
)


class FactorIn(BaseModel):
    model_config = _FINITE

    name: str = Field(..., min_length=1, max_length=64)
    low: float
    high: float
    unit: str = Field("", max_length=16)
    log: bool = False

    @model_validator(mode="after")
    def _levels(self) -> "FactorIn":
        if not self.low < self.high:
            raise ValueError(f"low ({self.low:g}) must be below high ({self.high:g})")
        if self.log and self.low <= 0:
            raise ValueError("a log-scale factor needs positive levels")
        return self


class DesignIn(BaseModel):
    """Two-level design: full factorial or a fraction from explicit generators, plus centre runs."""

    model_config = _FINITE

    type: Literal["full", "fractional"] = "full"
    generators: list[Annotated[str, Field(max_length=MAX_GENERATOR_CHARS)]] | None = Field(
        None, max_length=14, description="fractional only, e.g. ['D=ABC'] for the thesis's 2^(4-1) design (Table A.8)"
    )
    centre_runs: WholeNumber = Field(3, ge=0, le=50, description="centre replicates, each with its own seed")
    replicates: WholeNumber = Field(1, ge=1, le=10)
    randomise: bool = True
    axial: Literal["none", "face"] = Field(
        "none", description="'face': add face-centred axial runs (2 per factor), making a central composite "
        "design whose fit has squared terms (what the surface check proposes after curvature or lack of fit)")

    @model_validator(mode="after")
    def _generators(self) -> "DesignIn":
        if self.type == "fractional" and not self.generators:
            raise ValueError("a fractional design needs generators, e.g. ['D=ABC']")
        if self.type == "full" and self.generators:
            raise ValueError("generators apply to fractional designs only")
        return self


class DesignPreviewIn(DesignIn):
    """A design preview is DEM-agnostic: any factor names."""

    factors: list[FactorIn] = Field(..., min_length=1, max_length=15)
    seed: WholeNumber = Field(0, ge=0, le=2**32 - 1)


class PriorIn(BaseModel):
    model_config = _FINITE

    parameter: str = Field(..., max_length=64)
    value: float
    uncertainty: float = Field(..., gt=0)
    source: str = Field("", max_length=MAX_SOURCE_CHARS, description="where the value comes from (a reference)")


class LoopSettings(BaseModel):
    """How one calibration loop runs: what it varies, what it holds fixed, how it judges and when it
    stops. The notebook loop (``calibration.loop``) and a campaign (``service.campaigns``: this plus
    a name, a material, an evaluator, targets and a priority) read the same settings, so the same
    batteries give the same answers in both."""

    model_config = _FINITE

    fidelity: Literal["screening", "thesis"] = "screening"
    resolution: ResolutionIn | None = Field(
        None, description="'as_measured' or 'coarse' (or {mode, scale_factor | target_particles}): the material's "
        "particles, as described or coarse-grained, in the rig its measurements were made in, so that every "
        "quantity is simulated in that apparatus (engine.lab.resolution); 'thesis' or 'screening': the preset of "
        "that name, the same as fidelity; unset: fidelity's preset")
    rig: Rig | None = Field(None, description="with resolution as_measured or coarse: the apparatus; a campaign "
                                              "takes its material's")
    particles: Particles | None = Field(None, description="with resolution as_measured or coarse: the particles; "
                                                          "a campaign takes its material's")
    test: JobTestName = Field(
        BATTERY, description="what each run simulates: the fill -> CCT -> DST battery, or one test alone"
    )
    factors: list[FactorIn] = Field(..., min_length=1, max_length=8)
    design: DesignIn = Field(default_factory=DesignIn)
    fixed_parameters: MicroParametersDict = Field(
        default_factory=dict, description="MicroParameters held fixed (and contact effects) for every run"
    )
    options: TestOptionsDict = Field(default_factory=dict, description="TestOptions of every battery")
    default_relative_uncertainty: float = Field(
        0.05, gt=0, le=1,
        description="standard uncertainty assumed, relative to the mean, for a target published without replicates",
    )
    model_discrepancy: list[Discrepancy] = Field(
        default_factory=list, max_length=64,
        description="model-form discrepancy per test (calibration.discrepancy): a mismatch of this size, which "
                    "no parameter and no effect is meant to fix, is not read as a missing effect; none: the "
                    "model is taken as exact apart from its parameters and the candidate effects")
    constraints: list[Annotated[str, Field(max_length=MAX_CONSTRAINT_CHARS)]] = Field(
        default_factory=list, max_length=50, description="linear constraints on factors, e.g. 'friction_pw <= friction_pp'"
    )
    priors: list[PriorIn] = Field(
        default_factory=list, max_length=8, description="directly measured factors (e.g. particle density) with uncertainty"
    )
    allow_extrapolation: bool = False
    diagnose: bool = Field(
        True, description="after a report that is not 'calibrated', run a baseline and each candidate effect at the "
        "optimum, at one seed of their own and at more (up to the confirmation's number) where they buy power "
        "(adaptive_replicates), and rank the missing effects (docs/diagnosis.md)",
    )
    diagnose_always: bool = Field(
        False, description="run the diagnosis after every report, also one that passes with nothing flagged: "
        "its directed test (the candidates' score along their signatures) sees a misfit spread thinly over many "
        "targets that the omnibus lack of fit misses; costs a baseline and one battery per candidate, per confirmation seed",
    )
    confirmation_seeds: WholeNumber = Field(
        2, ge=1, le=8, description="batteries at the optimum, each with its own seed; the report compares their "
        "mean with the measurements, so the simulator's seed-to-seed scatter enters the lack of fit divided by "
        "this number, and the polishing steps and the diagnosis run at the same seeds (common random numbers). "
        "1 is cheapest; the diagnosis then adds a second seed at the optimum",
    )
    polish_steps: WholeNumber = Field(
        3, ge=0, le=6, description="Gauss-Newton steps on the batteries after the confirmation (0: none); each "
        "costs 3 batteries per confirmation seed, plus one per factor and seed for the Jacobian: the surfaces' "
        "optimum is biased inside the box for saturating responses",
    )
    polish_when: Literal["always", "surrogate_misses"] = Field(
        "surrogate_misses", description="'always': every iteration polishes; 'surrogate_misses' (the default): only an iteration whose "
        "confirmation batteries fall outside the response surfaces' prediction intervals (the report's "
        "surrogate_check), as the library loop does. Where the surfaces predict the optimum's batteries a "
        "polishing round buys little; where they miss (typically once an effect's strength is a fifth factor) "
        "the surfaces' optimum is not the simulator's and an effect that fits can look as if it did not; an "
        "iteration with an added effect is polished too when it misses at the surfaces' optimum (a target out of "
        "reach, a parameter at a bound, the lack of fit failing, a directly measured parameter missed by more "
        "than 2 sd), then with slopes measured on the batteries if the surfaces predicted them",
    )
    adaptive_replicates: bool = Field(
        True, description="the diagnosis runs a baseline and each candidate at one seed first, and at the other "
        "confirmation seeds only when the decision is close and the simulator's scatter matters "
        "(calibration.replicates); false runs every seed at once",
    )
    reuse: bool = Field(
        True, description="an iteration after the first reuses the batteries earlier iterations ran at points "
        "of its own model (calibration.reuse): design points they sit on are not run again, and the rest "
        "(confirmation, polishing, diagnosis) join the response surfaces' fit; false runs every design point",
    )
    polish_jacobian: Literal["surfaces", "batteries"] = Field(
        "surfaces", description="the polishing's first Jacobian: 'surfaces', the response surfaces' slopes at the "
        "optimum (no batteries; Broyden's updates correct it along the steps), or 'batteries', forward "
        "differences on the batteries (one point per factor and seed). An iteration polished although its "
        "surfaces predicted the optimum's batteries (an added effect missing at their optimum) measures them on "
        "the batteries whatever this says: the surfaces' slopes lead back to their own optimum",
    )
    polish_holdout: bool = Field(
        True, description="after a polish that took a step, run the chosen point again at confirmation_seeds "
        "fresh seeds, and let the report, its lack of fit and the diagnosis read those batteries: the steps "
        "kept the trial whose batteries happened to fit best, so the same batteries flatter it (a winner's "
        "curse: on DEM's hertz_strong a targets chi2 of 15.8 on the chosen seeds, 28.4 on 16 others). Costs "
        "confirmation_seeds batteries per polished iteration; false reads the polish's own batteries",
    )
    automatic: bool = Field(
        False, description="after each iteration, add the effect the diagnosis indicates and run the next "
        "iteration by itself, until the lack of fit passes, nothing improves, or max_iterations is reached "
        "(the reason is in the summary's stop_reason)",
    )
    max_iterations: WholeNumber = Field(4, ge=1, le=MAX_ITERATIONS, description="automatic mode: iterations at most, the first included")
    seed: WholeNumber = Field(0, ge=0, le=2**31 - 1_000_000)
    @field_validator("factors")
    @classmethod
    def _factor_names(cls, factors: list[FactorIn]) -> list[FactorIn]:
        names = [f.name for f in factors]
        for name in names:
            if name not in FACTOR_NAMES:
                try:  # an effect's parameter, e.g. effects.rolling_epsd2.rolling_friction
                    factor_paths.check_factor(name)
                except ValueError as exc:
                    raise ValueError(f"factor {name!r} is not a micro parameter ({', '.join(FACTOR_NAMES)}) "
                                     f"nor an effect parameter: {exc}") from None
        if len(set(names)) != len(names):
            raise ValueError("factor names repeat")
        return factors

    @field_validator("fixed_parameters")
    @classmethod
    def _fixed(cls, fixed: dict[str, Any], info: ValidationInfo) -> dict[str, Any]:
        MicroParameters.model_validate(fixed)  # raises with the field named
        if "particle_radius_m" in fixed and not is_preset(info.data.get("resolution")):
            raise ValueError("particle_radius_m sets the screening preset's spheres; at a material resolution the "
                             "sizes are the particles' (times the coarse factor)")
        return fixed

    @field_validator("rig", "particles")
    @classmethod
    def _with_material_resolution(cls, value, info: ValidationInfo):
        if value is not None and "resolution" in info.data and is_preset(info.data["resolution"]):
            raise ValueError(f"a preset (fidelity, or resolution 'thesis'/'screening') brings its own "
                             f"{info.field_name}; send resolution 'as_measured' or 'coarse' to run this {info.field_name}")
        return value

    @field_validator("resolution")
    @classmethod
    def _one_preset(cls, resolution: ResolutionIn | None, info: ValidationInfo) -> ResolutionIn | None:
        fidelity = info.data.get("fidelity")
        if resolution in PRESET_NAMES and fidelity not in (None, "screening", resolution):
            raise ValueError(f"resolution {resolution!r} and fidelity {fidelity!r} name different presets; send one")
        return resolution

    def lab(self) -> dict[str, Any]:
        """Where each battery runs, as JobSpec fields: the preset, or the resolution with the rig and particles."""
        if is_preset(self.resolution):
            return {"fidelity": self.fidelity}
        return {"fidelity": self.fidelity, "resolution": self.resolution, "rig": self.rig, "particles": self.particles}

    @field_validator("options")
    @classmethod
    def _options(cls, options: dict[str, Any]) -> dict[str, Any]:
        TestOptions.model_validate(options)
        return options

    @model_validator(mode="after")
    def _no_overlap(self) -> "LoopSettings":
        if self.resolution in PRESET_NAMES:
            self.fidelity = self.resolution  # the alias names the preset every reader of fidelity sees
        if not is_preset(self.resolution) and any(f.name == "particle_radius_m" for f in self.factors):
            raise ValueError("factor particle_radius_m varies the screening preset's spheres; at a material "
                             "resolution the sizes are the particles' (vary resolution.scale_factor between iterations)")
        if self.automatic and not self.diagnose:
            raise ValueError("automatic mode needs diagnose: it adds the effects the diagnosis indicates")
        if self.diagnose_always and not self.diagnose:
            raise ValueError("diagnose_always needs diagnose")
        overlap = {f.name for f in self.factors} & set(self.fixed_parameters)
        if overlap:
            raise ValueError(f"fixed_parameters: {sorted(overlap)} are factors too")
        names = {f.name for f in self.factors}
        for index, text in enumerate(self.constraints):
            try:
                constraint = parse_constraint(text)
            except DoeError as exc:
                raise ValueError(f"constraints[{index}]: {exc}") from None
            unknown = set(constraint.parameters) - names
            if unknown:
                raise ValueError(f"constraints[{index}] uses {sorted(unknown)}, which are not factors")
        for index, prior in enumerate(self.priors):
            if prior.parameter not in names:
                raise ValueError(f"priors[{index}]: a prior on {prior.parameter!r}, which is not a factor "
                                 "(only factors can have priors)")
        for factor in self.factors:  # each corner must be a valid micro parameter set
            for level in (factor.low, factor.high):
                MicroParameters.model_validate(factor_paths.apply(self.fixed_parameters, {factor.name: level}))
        return self




def validated(raw: dict[str, Any]) -> dict[str, Any]:
    """``raw`` with the loop's settings in it validated (``LoopSettings``) and returned as stored JSON;
    keys that are not the loop's (a campaign's name, material, evaluator) pass through unchanged."""
    ours = LoopSettings.model_validate({k: v for k, v in raw.items() if k in LoopSettings.model_fields})
    return {**raw, **ours.model_dump(mode="json")}
