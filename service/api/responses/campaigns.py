"""A campaign's summary, its iterations and runs, and the products of an iteration before its report:
design, fitted models, optimum, confirmation (service.campaigns.store views and the campaign routes)."""
from __future__ import annotations

from typing import Any

from pydantic import Field

from calibration.vocabulary import Phase, RunKind
from service.api.responses.common import (
    CONDITION,
    PARAMETERS,
    Condition,
    CostEstimate,
    Factor,
    Out,
    Page,
    ParameterValues,
)
from service.api.responses.designs import DesignView
from service.api.responses.report import Report
from service.vocabulary import CampaignStatus, RunStatus


class CampaignSummary(Out):
    """State, iteration, phase and run counts of a campaign (store.campaign_summary)."""

    id: int
    name: str
    material_id: int
    status: CampaignStatus
    evaluator: str = Field(description="'dem' or 'analytic'")
    fidelity: str
    current_iteration: int = Field(description="0 before the start")
    phase: Phase | None = Field(description="the current iteration's phase; null before the start")
    runs_total: int = Field(description="runs of the current iteration")
    runs_succeeded: int
    runs_failed: int = Field(description="failed or cancelled runs of the current iteration")
    error: str | None = Field(description="why the campaign failed")
    schedule_id: int | None = Field(description="the schedule that created it")
    owner: str | None = Field(None, description="the user (bearer token name) who made it; null when made without a token")
    created_at: str | None = Field(description="ISO 8601, UTC ('Z')")
    started_at: str | None
    finished_at: str | None
    config: dict[str, Any] = Field(description="the configuration of the next or current iteration: the "
                                               "fields of the create body (CampaignCreate), as validated")
    stop_reason: str | None = Field(description="automatic mode: why the loop stopped")
    continuable: bool = Field(False, description="automatic mode: it stopped where more iterations could go on (at "
                              "the iteration limit, or with an alias of the kept effect left unfitted): POST "
                              ".../continue")
    kept_iteration: int | None = Field(None, description="automatic mode: the iteration whose model the loop kept "
                                                         "when that is not the last (an alias fitted in its place "
                                                         "and compared with it)")
    warnings: list[str] = Field(default_factory=list,
                                description="factor ranges, fixed parameters and options outside their typical "
                                            "ranges, each with the unit slip it probably is "
                                            "(engine.lab.plausibility); accepted, not refused")
    estimate: CostEstimate | None = Field(None, description="at creation (POST): each battery's particles and "
                                                         "simulated time in the campaign's rig and resolution")


class CampaignList(Page):
    """A page of campaigns, newest first."""

    items: list[CampaignSummary]


class Response(Out):
    """One simulated response of a battery, keyed like a measurement."""

    test: str
    quantity: str
    condition: Condition = Field(description=CONDITION)
    unit: str
    value: float | None = Field(description="in the unit above (SI)")


class Run(Out):
    """One battery of an iteration (store.run_view)."""

    id: int
    kind: RunKind
    std_order: int
    run_order: int
    is_centre: bool
    coded: dict[str, float | None] | None = Field(description="per factor: coded level")
    natural: ParameterValues | None = Field(description=PARAMETERS)
    seed: int
    job_id: int | None = Field(description="the queued job; null before queueing")
    status: RunStatus
    responses: dict[str, Response] | None = Field(description="per response name: the battery's value")
    error: str | None
    reused_from: str | None = Field(None, description="a battery an earlier iteration ran, reused here (not run "
                                                      "again), e.g. 'iteration 1 design run 5'; null: run for this iteration")


class IterationParameters(Out):
    """What an iteration varies and holds fixed."""

    factors: list[Factor] = Field(default_factory=list)
    fixed: dict[str, Any] = Field(default_factory=dict, description="micro-parameters held fixed (SI)")
    effects: dict[str, Any] = Field(default_factory=dict, description="contact effects held fixed, by name")
    options: dict[str, Any] = Field(default_factory=dict, description="lab test options")
    evaluator: str | None = None
    fidelity: str | None = None
    lab: dict[str, Any] | None = Field(
        None, description="where the iteration's batteries run: fidelity (a preset), or resolution with the rig and "
        "particles (calibration.reuse.lab_json); none on iterations stored before session 20")
    setup_key: str | None = Field(
        None, description="digest of what the iteration's batteries run besides their micro parameters (test, preset "
        "or resolution with rig and particles, options, evaluator): a later iteration reuses only batteries of the same "
        "key (calibration.reuse.setup_key); none on iterations stored before session 19")


class Iteration(Out):
    """One iteration with its parameters, design, report and runs (store.iteration_view)."""

    number: int
    phase: Phase = Field(description="where the iteration is (calibration.vocabulary.Phase)")
    parameters: IterationParameters | None
    effects: list[str] = Field(description="the effects in the iteration's model (Candidate.active_in: fixed "
                                           "contact effects, strengths that are factors, a shape off 1)")
    design: DesignView | None
    created_at: str | None
    finished_at: str | None
    report: Report | None = Field(description="as GET /campaigns/{id}/report without its campaign fields")
    runs: list[Run] = Field(default_factory=list)


class IterationList(Page):
    """A page of a campaign's iterations, in the order they were run (number ascending)."""

    items: list[Iteration]


class CampaignDesign(DesignView):
    iteration: int


class FitStatistics(Out):
    n_runs: int | None = None
    n_coefficients: int | None = None
    df_residual: int | None = None
    std_dev: float | None = None
    mean: float | None = None
    cv_percent: float | None = None
    r_squared: float | None = None
    adj_r_squared: float | None = None
    pred_r_squared: float | None = None
    press: float | None = None


class AnovaRow(Out):
    source: str = Field(description="a term, 'Model', 'Residual', 'Lack of Fit', 'Pure Error', 'Curvature' or 'Cor Total'")
    sum_of_squares: float | None
    df: int
    mean_square: float | None = None
    f_value: float | None = None
    p_value: float | None = None


class Fit(Out):
    """A fitted response surface (doe.fit.ResponseFit.to_dict)."""

    response: str
    transform: str = Field("none", description="'log': fitted to ln(y) (Box-Cox, doe.transform); coefficients, "
                           "ANOVA and effects on that scale, predictions transformed back")
    terms: list[str]
    factors: list[Factor]
    coefficients_coded: list[dict[str, Any]] = Field(description="per term: estimate, standard error, t, p")
    coefficients_natural: list[dict[str, Any]] = Field(description="per term in natural units: name, estimate, std_error")
    equation_coded: str
    equation_natural: str
    anova: list[AnovaRow]
    has_error_estimate: bool
    fit_statistics: FitStatistics
    effects: dict[str, Any] | None = Field(description="effect estimates of a two-level design")
    messages: list[str]
    reduction_log: list[Any]


class TargetModel(Out):
    """One target's fitted model (calibration.fitting.TargetModel.to_dict)."""

    test: str
    quantity: str
    condition: Condition = Field(description=CONDITION)
    unit: str | None = None
    measurement_id: int | None = None
    response: str | None = Field(None, description="the matched response name; null when not simulated")
    status: str | None = None
    ok: bool = Field(description="a model was fitted")
    error: str | None = None
    pure_error_sd: float | None = Field(None, description="simulator noise from the centre replicates, in the unit")
    values: list[float | None] = Field(default_factory=list, description="the response in each run, standard order")
    fit: Fit | None = None


class CampaignModels(Out):
    iteration: int
    models: dict[str, TargetModel] = Field(description="per response name")


class Prediction(Out):
    value: float | None
    pi_low: float | None = Field(description="95% prediction interval of one battery")
    pi_high: float | None
    ci_low: float | None = Field(description="95% confidence interval of the mean")
    ci_high: float | None


class OptimumTarget(Out):
    measurement_id: int
    response: str
    test: str
    quantity: str
    condition: Condition = Field(description=CONDITION)
    measured: float
    uncertainty: float | None = Field(description="standard uncertainty of the measurement, its unit")
    uncertainty_assumed: bool = False
    uncertainty_source: str | None = None
    predicted: float | None
    pi_low: float | None
    pi_high: float | None
    standardised_residual: float | None
    reachability: float | None = Field(description="smallest |standardised misfit| over the design box")
    reachable: bool | None


class Reachability(Out):
    response: str
    test: str | None = None
    condition: Any = None
    target: float | None = None
    min_standardised_misfit: float | None = None
    reachable: bool | None = None
    closest_prediction: float | None = None
    closest_parameters: ParameterValues | None = None


class Optimum(Out):
    """The optimised parameters with predictions and reachability (calibration.analysis.analyse,
    moved by polishing)."""

    parameters: ParameterValues = Field(description=PARAMETERS)
    coded: dict[str, float | None] | None = None
    parameter_std: ParameterValues | None = Field(None, description="standard deviation per factor, its unit")
    objective: float | None = None
    success: bool | None = None
    message: str | None = None
    predictions: dict[str, Prediction] | None = Field(None, description="per response name")
    targets: list[OptimumTarget] | None = None
    active_bounds: list[dict[str, Any]] | None = Field(None, description="parameters at a bound: parameter, side, value")
    active_constraints: list[Any] | None = None
    constraints: list[Any] | None = None
    priors: list[dict[str, Any]] | None = None
    reachability: list[Reachability] | None = None
    polish: dict[str, Any] | None = Field(None, description="the polishing's state (calibration.polish)")
    surrogate_parameters: ParameterValues | None = Field(None, description="the surfaces' optimum before polishing")


class CampaignOptimum(Optimum):
    iteration: int


class ConfirmationRun(Out):
    job_id: int | None
    status: RunStatus
    seed: int
    responses: dict[str, Response] | None
    error: str | None


class Confirmation(ConfirmationRun):
    """The batteries at the optimum, one per seed; the top level is the first seed's."""

    iteration: int
    parameters: ParameterValues | None = Field(description=PARAMETERS)
    coded: dict[str, float | None] | None
    runs: list[ConfirmationRun]
