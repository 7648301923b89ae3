"""The history of a campaign: per iteration the effects, optimum, weighted error overall and per test,
verdict and the effect added next; per target its standardised residual in each iteration."""
from __future__ import annotations

from pydantic import Field

from calibration.vocabulary import Verdict
from service.api.responses.common import (
    CONDITION,
    PARAMETERS,
    Condition,
    Out,
    ParameterValues,
)
from service.api.responses.report import Continued, Decision, Explanation


class IterationBatteries(Out):
    """What an iteration ran (calibration.history.batteries)."""

    design: int = Field(description="design batteries run for this iteration")
    confirmation: int
    polish: int
    diagnosis: int
    reused: int = Field(description="design rows that are earlier iterations' batteries (not run again)")
    total: int = Field(description="batteries run for this iteration, every phase")
    why: list[str] = Field(default_factory=list, description="why each phase ran as many as it did")


class HistoryEntry(Out):
    number: int = Field(description="iteration number")
    effects: list[str] = Field(description="candidate effects in the iteration's model")
    added_effect: list[str] | None = Field(description="effects added relative to the iteration it was built on")
    optimum: ParameterValues | None = Field(description=PARAMETERS)
    parameter_std: ParameterValues | None = Field(description="the optimiser's standard deviation per factor (the "
                                                              "targets' uncertainty alone), its unit")
    parameter_interval: dict[str, list[float]] | None = Field(
        None, description="per factor [low, high] of the report's 95 % interval (measurement, simulator, misfit; "
                          "cut at the design box), its unit; null before the iteration has a report")
    chi2: float | None = Field(description="lack-of-fit statistic")
    chi2_per_dof: float | None
    dof: int | None
    noise_band: list[float | None] | None = Field(description="[low, high] of chi2 / dof by chance")
    lack_of_fit_p: float | None
    adequacy_p: float | None = Field(description="once diagnosed: Holm over lack of fit and directed test")
    directed_p: float | None = Field(description="once diagnosed: the candidates' directed test")
    per_test: dict[str, float] = Field(description="per lab test: its chi2")
    weighted_rms: float | None = Field(description="RMS of the modelled targets' standardised residuals")
    verdict: Verdict | None
    top_effect: str | None = Field(description="the diagnosis's first-ranked effect")
    decision: Decision | None = Field(description="automatic mode: whether the added effect was kept")
    stop_reason: str | None = Field(description="automatic mode: why the loop stopped here")
    continued: Continued | None = Field(None, description="automatic mode: the loop had stopped here and was taken up "
                                                          "again with more iterations (POST .../continue)")
    range_widened: bool = Field(description="the iteration redid its base on a wider strength range")
    box_widened: list[str] = Field(default_factory=list, description="base factors this iteration ran in a wider box "
                                                                     "than the iteration it was built on (their optimum "
                                                                     "sat on an edge short of their typical range)")
    effect_added_next: list[str] | None = Field(description="what the next iteration added")
    tie_break: str | None = Field(None, description="automatic mode: the candidates the diagnosis could not tell "
                                                    "apart and why the next effect went first among them")
    kept_iteration: int | None = Field(None, description="automatic mode, where the loop fitted an alias in place of "
                                                         "an effect that passed: the iteration whose model it keeps")
    undistinguished: list[str] | None = Field(None, description="the two aliased effects whose fits the measurements "
                                                                "could not tell apart (chi2 within 2)")
    explains: Explanation | None = Field(None, description="how much of the misfit the added effect explains")
    batteries: IterationBatteries | None = Field(None, description="batteries run per phase, design rows reused, and why")


class HistoryTarget(Out):
    test: str
    quantity: str
    condition: Condition = Field(description=CONDITION)
    residuals: dict[str, float | None] = Field(description="per iteration number (as text): standardised residual")


class History(Out):
    """GET /campaigns/{id}/history."""

    campaign_id: int
    iterations: list[HistoryEntry] = Field(description="the iterations with a report, in order")
    targets: dict[str, HistoryTarget] = Field(description="per response name (or quantity) of a modelled target")
