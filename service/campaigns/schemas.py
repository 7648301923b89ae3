"""Campaign configuration as users send it; validated once, stored as JSON, re-read by the runner.

The loop's own settings (factors, design, priors, the loop's rules) are ``calibration.settings``; a
campaign adds what the service needs to run them: a name, a material and which of its measurements are
targets, an evaluator and a queue priority."""
from __future__ import annotations

from typing import Any

from pydantic import BaseModel, Field, ValidationInfo, field_validator, model_validator

from calibration.evaluator_registry import DEFAULT, EvaluatorName
from calibration.settings import _FINITE, MAX_ITERATIONS, DesignIn, DesignPreviewIn, FactorIn, LoopSettings, PriorIn  # noqa: F401
from engine.lab.bounds import ID_MAX, CONDITION_BOUNDS
from engine.lab.registry import known_quantity, known_test
from engine.lab.resolution import ResolutionIn
from engine.lab.spec import STRICT_PAIR, MicroParameters, MicroParametersDict, TestOptions, TestOptionsDict, WholeNumber
from engine.lab.units import UnitError, condition_si_unit

# One priority scale for jobs and campaigns (service.api.params mirrors it for jobs).
PRIORITY_MIN, PRIORITY_MAX = -1000, 1000


class TargetIn(BaseModel):
    model_config = _FINITE

    test: str = Field(..., max_length=32)
    quantity: str = Field(..., max_length=64)
    condition: dict[str, float] = Field(default_factory=dict, max_length=8)

    @field_validator("condition")
    @classmethod
    def _condition(cls, condition: dict[str, float]) -> dict[str, float]:
        """SI conditions (as stored with measurements), within the bounds of their unit."""
        for name, value in condition.items():
            try:
                CONDITION_BOUNDS[condition_si_unit(name)].check(value, f"condition {name}")
            except UnitError as exc:
                raise ValueError(str(exc)) from None
        return condition

    @field_validator("test")
    @classmethod
    def _known_test(cls, test: str) -> str:
        return known_test(test)

    @field_validator("quantity")
    @classmethod
    def _known_quantity(cls, quantity: str, info: ValidationInfo) -> str:
        return known_quantity(info.data.get("test"), quantity)


class CampaignCreate(LoopSettings):
    """A calibration loop the service runs: the loop's settings on one material's measurements."""

    model_config = _FINITE

    name: str = Field(..., min_length=1, max_length=200)
    material_id: WholeNumber = Field(..., ge=1, le=ID_MAX)
    evaluator: EvaluatorName = Field(DEFAULT.name, description="the backend every run goes to (GET /api/v1/evaluators)")
    targets: list[TargetIn] | None = Field(
        None, max_length=1000, description="measurements to calibrate against; default every measurement the battery simulates"
    )
    priority: WholeNumber = Field(0, ge=PRIORITY_MIN, le=PRIORITY_MAX, description="of every job the campaign queues")


class IterationIn(BaseModel):
    """Changes for the next iteration of a completed campaign (e.g. a contact effect added).

    Whatever is not given is carried over from the previous iteration's configuration.
    """

    model_config = _FINITE

    # Validated here, before the campaign's state is looked at: a bad effect is a 422 whatever the
    # campaign is doing.
    @field_validator("fixed_parameters")
    @classmethod
    def _fixed(cls, fixed: dict[str, Any] | None) -> dict[str, Any] | None:
        if fixed is not None:
            MicroParameters.model_validate(fixed)
        return fixed

    @field_validator("options")
    @classmethod
    def _options(cls, options: dict[str, Any] | None) -> dict[str, Any] | None:
        if options is not None:
            TestOptions.model_validate(options)
        return options

    fixed_parameters: MicroParametersDict | None = Field(
        None, description="replaces the fixed micro parameters, e.g. with effects={'rolling_epsd2': {...}}"
    )
    factors: list[FactorIn] | None = Field(None, min_length=1, max_length=8)
    design: DesignIn | None = None
    targets: list[TargetIn] | None = Field(None, max_length=1000)
    options: TestOptionsDict | None = None
    resolution: ResolutionIn | None = Field(
        None, description="the next iteration's resolution (e.g. a coarse factor nearer 1, or 'as_measured' to confirm "
        "at the particles' own size): at a material resolution the runs are built in the material's rig with its "
        "particles; batteries of another resolution are not reused")
    add_effect: str | None = Field(
        None, max_length=64, description="a diagnosis candidate (GET /api/v1/effects) whose strength becomes one more design "
        "factor, keeping the previous factors: from 'off' over its plausible range, or to twice the last "
        "diagnosis's estimate of the strength if larger (a switch-type effect: a log range of 4x about its "
        "value matched at the last optimum), or strength_range",
    )
    strength_range: STRICT_PAIR | None = Field(None, strict=False, description="low, high of the added effect's strength")
    override: bool = Field(
        False, description="add_effect against the last diagnosis: when it found no physical match or a suspect "
        "measurement, an effect is added only with override true (the diagnosis says no effect explains the misfit)",
    )
    proposed_design: bool = Field(
        False, description="run the design the last iteration's surface check proposed (report.surrogate_check: "
        "a narrowed factorial about the optimum, or face-centred axial runs for a central composite design)",
    )

    @field_validator("add_effect")
    @classmethod
    def _known_effect(cls, name: str | None) -> str | None:
        if name is not None:
            from engine.candidates import get as get_candidate

            get_candidate(name)  # ValueError naming the candidates
        return name

    @model_validator(mode="after")
    def _range(self) -> "IterationIn":
        if self.strength_range is not None:
            if self.add_effect is None:
                raise ValueError("strength_range needs add_effect")
            if not self.strength_range[0] < self.strength_range[1]:
                raise ValueError("strength_range: low must be below high")
        if self.override and self.add_effect is None:
            raise ValueError("override needs add_effect")
        if self.add_effect is not None and self.factors is not None:
            raise ValueError("give either factors or add_effect, not both")
        if self.proposed_design and (self.factors is not None or self.design is not None):
            raise ValueError("proposed_design sets the factors' ranges or the design itself: give neither with it")
        return self


class ContinueIn(BaseModel):
    """More iterations for a completed automatic campaign (calibration.machine.extended)."""

    model_config = _FINITE

    more_iterations: WholeNumber = Field(
        1, ge=1, le=MAX_ITERATIONS - 1, description="iterations beyond the last one; the loop's limit becomes the "
        f"last iteration's number plus this (at most {MAX_ITERATIONS} in all)")
