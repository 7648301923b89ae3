"""The report of an iteration, per target and as one verdict (calibration.report.build_report, with
the polish summary, the diagnosis and its adequacy test, and the automatic mode's record)."""
from __future__ import annotations

from typing import Any, Literal

from pydantic import Field

from calibration.vocabulary import Explains, Probe, Verdict
from service.api.responses.common import (
    CONDITION,
    PARAMETERS,
    Condition,
    LackOfFit,
    Out,
    ParameterValues,
)
from service.api.responses.designs import DesignView
from service.api.responses.diagnosis import Diagnosis, DirectedTest


class TargetRow(Out):
    """One measurement against the model. Which keys are present depends on ``status``: a target that was
    not simulated has no ``response`` or ``confirmed``; one that was not modelled no prediction."""

    measurement_id: int
    test: str
    quantity: str
    condition: Condition = Field(description=CONDITION)
    unit: str
    input_unit: str | None = Field(None, description="the unit the values were typed in")
    measured: float = Field(description="mean of the replicates, in the unit (SI)")
    n: int = Field(description="replicates")
    status: str = Field(description="modelled, not_modelled or not_simulated")
    note: str | None = Field(None, description="why a target is not modelled or not simulated; for a "
                                               "modelled one, that its surface rests on fewer runs than the design "
                                               "had, or was fitted to ln(y)")
    response: str | None = Field(None, description="the matched response name")
    confirmed: float | None = Field(None, description="mean of the confirmation batteries, in the unit")
    confirmed_per_seed: list[float | None] | None = None
    measured_uncertainty: float | None = Field(None, description="standard uncertainty, in the unit")
    uncertainty_assumed: bool | None = Field(None, description="from the default relative uncertainty")
    predicted: float | None = Field(None, description="the surfaces' prediction at the optimum")
    prediction_interval: list[float | None] | None = Field(None, description="[low, high] for the mean of the seeds")
    predicted_standardised_residual: float | None = None
    simulator_sd: float | None = Field(None, description="the simulator's scatter at the optimum, in the unit")
    residual_sd: float | None = Field(None, description="sqrt(u^2 + simulator_sd^2 / seeds), in the unit")
    standardised_residual: float | None = Field(None, description="(confirmed - measured) / residual_sd")
    confirmation_in_interval: bool | None = None
    reachability: float | None = Field(None, description="smallest |standardised misfit| in the design box")
    reachable: bool | None = Field(None, description="reachability below the report's reachable_limit")
    reached_by: str | None = Field(None, description="set when the surfaces called the target out of reach but the "
                                                     "batteries at the polished optimum reached it")


class TestShare(Out):
    """One test's share of the misfit, Holm-corrected."""

    test: str = Field(description="a lab test, or 'prior'")
    n: int
    chi2: float
    share: float = Field(description="chi2 / total chi2")
    p_value: float | None
    p_holm: float | None = None
    fails: bool | None = None


class ActiveBound(Out):
    parameter: str
    side: str = Field(description="'low' or 'high'")
    value: float | None
    pushes: str = Field(description="'higher' or 'lower'")
    meaning: str


class PriorPulled(Out):
    """A prior the calibration pulls more than 2 sd off its measured value."""

    parameter: str
    value: float = Field(description="the prior's value, in the parameter's unit")
    uncertainty: float = Field(description="the prior's standard uncertainty, same unit")
    source: str = ""
    standardised_residual: float = Field(description="(calibrated - value) / uncertainty")
    meaning: str


class Conflicts(Out):
    active_bounds: list[ActiveBound] = Field(default_factory=list)
    priors_pulled: list[PriorPulled] = Field(default_factory=list)


class SurfaceResponse(Out):
    response: str
    observed: float | None
    predicted: float | None
    pi_low: float | None
    pi_high: float | None
    inside: bool | None


class SurrogateCheck(Out):
    """The fitted response surfaces against the batteries at the optimum (doe.confirm): a check of the
    surrogate, not of the model against the measurements."""

    verdict: str = Field(description="confirmed, not confirmed or not testable")
    confirmed: bool | None = None
    reason: str | None = None
    next_design_kind: str | None = Field(None, description="narrowed_factorial or augment_ccd")
    responses: list[SurfaceResponse] | None = None
    n_observations: int | None = Field(None, description="confirmation batteries averaged")
    about: str | None = None
    next_design: DesignView | None = Field(None, description="the design the check proposes")


class PolishAnchor(Out):
    """One point of a missed measured parameter's profile that the polish ran (calibration.polish)."""

    held: dict[str, float] = Field(description="the measured parameter held, at its measured value (clipped to its box)")
    parameters: ParameterValues = Field(description=PARAMETERS)
    chi2: float | None = Field(None, description="chi2 of its batteries (priors included); None before they ran")
    taken: bool = Field(False, description="the steps started here: its batteries fit better than the optimum's")
    step_chi2: float | None = Field(None, description="chi2 of one Gauss-Newton step from it, tried beside the "
                                    "optimum's first step when it was not taken; None when none was tried")
    step_taken: bool = Field(False, description="that step fitted the batteries best of the round's trials and "
                             "the polish went on from there")


class Polish(Out):
    """Gauss-Newton steps on the batteries after the surfaces' optimum (calibration.polish.summary)."""

    steps: int = Field(description="Gauss-Newton steps taken; starting at an anchor (``anchors``, ``taken``) is not one")
    batteries: int
    chi2_start: float | None = None
    chi2: float | None = None
    parameters: ParameterValues | None = Field(None, description=PARAMETERS)
    skipped: str | None = Field(None, description="why no step was taken")
    why: str | None = Field(None, description="why the iteration polished (calibration.machine: the surfaces "
                            "missed the confirmation, or an added effect misses the measurements at their optimum)")
    jacobian: str | None = Field(None, description="where the first Jacobian came from: 'surfaces' or 'batteries'")
    anchors: list[PolishAnchor] | None = Field(None, description="the surfaces' optimum with a missed measured "
                                               "parameter held at its measured value, run on the batteries")
    seeds: list[int] | None = Field(None, description="the seeds every polishing point ran at (the confirmation's)")
    holdout_seeds: list[int] | None = Field(None, description="after a step: the fresh seeds the chosen point ran at "
                                            "once more (polish_holdout); the report and the diagnosis read these "
                                            "batteries, on which no trial was chosen")
    holdout_chi2: float | None = Field(None, description="chi2 (priors included) of the held-out batteries: beside "
                                       "chi2, the steps' best on their own seeds, it shows how much of the polish's "
                                       "gain was the noise of the batteries it chose on")


class Adequacy(Out):
    """The diagnosis's adequacy test: Holm over the omnibus lack of fit and the candidates' directed test."""

    p_value: float | None
    fails: bool
    about: str | None = None
    omnibus_p: float | None = None
    directed: DirectedTest | None = None


class Remaining(Out):
    """The misfit an added effect leaves (calibration.decisions.explanation)."""

    verdict: Verdict | None = None
    chi2_per_dof: float | None = None
    noise_band: list[float | None] | None = None
    p_value: float | None = Field(None, description="the adequacy test's p (the lack of fit's before a diagnosis)")
    failing_tests: list[str] = Field(default_factory=list)


class Explanation(Out):
    explains: Explains = Field(description="'explains' only when the iteration with the effect is calibrated")
    remaining: Remaining
    explains_message: str


class Decision(Out):
    """Whether an effect the automatic mode added earned its place (calibration.decisions.Decision), and
    how much of the misfit it explains."""

    effect: str
    accepted: bool
    chi2_before: float | None
    chi2_after: float | None
    lr: float | None = Field(description="likelihood-ratio statistic")
    p_value: float | None = Field(description="boundary-corrected LR test; null for a switch")
    delta_bic: float | None
    lof_p_before: float | None
    lof_p_after: float | None
    strength: float | None
    turned_off: bool = Field(False, description="the optimum put the effect at its off strength: never accepted; "
                             "an iteration in the noise that way is kept as the base model refitted")
    explains: Explains | None = Field(None, description="explains, partly explains or does not explain")
    remaining: Remaining | None = None
    explains_message: str | None = None


class Check(Out):
    """One check of the verdict (calibration.verdict.checks): what holds and what does not."""

    check: str
    holds: bool | None = Field(description="null: not made")
    detail: str


class SuspectMeasurement(Out):
    """A measured quantity far outside anything the model reaches (calibration.suspect)."""

    test: str
    quantity: str
    unit: str
    conditions: list[Condition]
    measured: list[float]
    responses: list[str]
    reach: list[float] = Field(description="[low, high] of every battery of the iteration (and the candidates')")
    ratio: float = Field(description="how many times beyond the reach")
    direction: str = Field(description="too small or too large")
    factor: float | None = Field(None, description="the unit slip that brings it back, e.g. 1000")
    meant_unit: str | None = Field(None, description="the unit it was probably meant in (known when the typed unit is)")
    message: str


class TieBreak(Out):
    """Candidates with one score (calibration.automatic.cheapest_of_equals): the cheapest battery is tried first."""

    equal: list[str]
    spheres: dict[str, int] = Field(description="spheres of the largest packing of a battery with each effect on")
    chosen: str
    message: str


class BoxWidening(Out):
    """A base factor's box edge moved out for the next iteration (calibration.decisions.widened_box)."""

    parameter: str
    side: str = Field(description="low or high")
    from_: float = Field(alias="from", description="the edge this iteration had, the factor's unit")
    to: float = Field(description="the edge the next iteration gets, within the parameter's typical range")


class KeptAlias(Out):
    """An effect kept although its base iteration's diagnosis found it aliased with candidates never fitted in
    its place (calibration.automatic.kept_alias)."""

    effect: str = Field(description="the effect kept")
    aliases: list[str] = Field(description="the alias group's other members, not fitted")
    base: int = Field(description="the iteration whose diagnosis grouped them")
    separating: list[str] = Field(description="the measurements that would tell them apart")
    message: str


class AliasRefit(Out):
    """The next iteration fits ``partner`` in place of ``leader``, which passed, on the same base
    (calibration.automatic.alias_refit)."""

    leader: str = Field(description="the effect kept, whose fit passed")
    leader_iteration: int
    partner: str = Field(description="its alias, never fitted, fitted next on the same base")
    base: int = Field(description="the iteration both are fitted on")
    message: str


class AliasSettled(Out):
    """The two aliases' fits compared (calibration.automatic.settle_alias)."""

    leader: str = Field(description="the effect first kept")
    partner: str = Field(description="its alias, fitted in its place")
    kept_iteration: int = Field(description="the iteration whose model the loop keeps")
    kept_effect: str
    undistinguished: list[str] | None = Field(description="both, where the measurements could not tell them apart")
    chi2: dict[str, float | None] = Field(description="per effect: its fit's chi2 on one variance per target")
    message: str


class Continued(Out):
    """A completed automatic loop taken up again after this iteration (calibration.machine.extended)."""

    more_iterations: int
    max_iterations: int = Field(description="the loop's limit from then on, the first iteration included")
    stopped_for: str | None = Field(description="the reason the loop had stopped here before")


class Automatic(Out):
    """The automatic mode's record of an iteration: its decision and the next step or why it stopped."""

    decision: Decision | None = None
    base_iteration: int | None = None
    next_effect: str | None = None
    next_base: int | None = None
    stop_reason: str | None = None
    widened: bool | None = Field(None, description="the next iteration redoes this one on a wider range")
    widened_box: list[BoxWidening] | None = Field(None, description="base factors the next iteration runs in a wider "
                                                                    "box: their optimum sat on an edge of this one")
    next_config: dict[str, Any] | None = Field(None, description="the next iteration's configuration (CampaignCreate)")
    tie_break: TieBreak | None = Field(None, description="the leading candidates the diagnosis could not tell apart "
                                                         "and why the next effect was tried first among them")
    aliased: KeptAlias | None = Field(None, description="the effect kept shares an alias group with candidates "
                                                        "never fitted: the fit does not say which is missing")
    alias_refit: AliasRefit | None = Field(None, description="the next iteration fits the kept effect's alias in "
                                                             "its place on the same base")
    alias_settled: AliasSettled | None = Field(None, description="the two aliases' fits compared: which is kept")
    kept_iteration: int | None = Field(None, description="the iteration whose model the loop keeps (after an "
                                                         "alias refit)")
    continued: Continued | None = Field(None, description="the loop had stopped here and was taken up again with "
                                                          "more iterations (POST .../continue)")


class Trend(Out):
    """A weighted straight line of residuals against the normal stress (calibration.localise.trends)."""

    description: str
    slope: float | None
    slope_se: float | None
    intercept: float | None
    intercept_se: float | None
    p_slope: float | None
    p_intercept: float | None
    x_centre: float | None
    n: int
    significant: bool | None = None
    measured_slope: float | None = None
    model_slope: float | None = None
    significant_slope: bool | None = None
    significant_intercept: bool | None = None
    measured_cohesion_pa: float | None = None
    measured_cohesion_se_pa: float | None = None
    model_cohesion_pa: float | None = None
    measured_friction_angle_deg: float | None = None
    model_friction_angle_deg: float | None = None


class Trends(Out):
    modulus_log_slope: Trend | None = Field(None, description="log(E' measured / model) against log(stress)")
    shear_stress: Trend | None = Field(None, description="shear stress residual (Pa) against normal stress (Pa)")
    dilatancy: Trend | None = Field(None, description="dilatancy residual (deg) against normal stress (Pa)")


class WaldInterval(Out):
    low: float
    high: float


class MeasuredPoints(Out):
    count: int = Field(description="points measured on the batteries at the final optimum's seeds (the surfaces' "
                       "optimum, the polish's Jacobian points, anchors and steps)")
    chi2_best: float = Field(description="the batteries' chi2 (priors included) at the final optimum")
    threshold: float = Field(description="chi2 above the best that the likelihood ratio does not reject at the "
                             "intervals' level: scale x quantile^2")
    widened: list[str] = Field(description="parameters whose interval a measured point widened")


class ParameterInterval(Out):
    value: float = Field(description="the optimum (natural units)")
    sd: float | None = Field(None, description="standard deviation; none when the data do not identify it")
    low: float | None = Field(None, description="lower end of the interval, cut at the factor's box")
    high: float | None = Field(None, description="upper end of the interval, cut at the factor's box")
    at_bound: list[str] | None = Field(None, description="sides where the interval was cut at the box")
    wald: WaldInterval | None = Field(None, description="the interval from the surfaces' slopes alone, where points "
                                      "measured on the batteries widened it (calibration.intervals.widen_to_measured)")


class Trade(Out):
    parameters: list[str]
    correlation: float
    message: str


class Intervals(Out):
    level: float = Field(description="coverage the intervals are built for")
    scale: float = Field(description="chi2/dof the covariance was widened by (1 while the lack of fit passes)")
    quantile: float = Field(description="normal, or t on the lack of fit's dof when widened")
    scaled_by_misfit: bool
    undetected_shift: bool = Field(False, description="the covariance holds, for each quantity without a stated "
                                   "model-form discrepancy, the shift shared by its rows that the lack of fit detects "
                                   "only half the time (calibration.intervals; false in reports made before it)")
    surface_error: bool = Field(False, description="the covariance holds the response surfaces' prediction error at "
                                "the optimum (calibration.intervals; false where no surface has an error estimate, "
                                "and in reports made before it)")
    parameters: dict[str, ParameterInterval]
    correlation: dict[str, dict[str, float | None]]
    trades: list[Trade] = Field(description="parameter pairs the measurements fix only in combination")
    unidentified: list[str]
    measured_points: MeasuredPoints | None = Field(None, description="the points measured on the batteries the "
                                                   "intervals were widened to (none before a confirmation's report "
                                                   "carried them)")
    about: str


class DiagnosisBattery(Out):
    effect: str = Field(description="candidate effect switched on, or 'baseline' (the optimum as it is)")
    seed: int
    probe: Probe = Field(Probe.STEP, description=(
        "where the candidate's strength was set: its secant step, or the top of its plausible range (a second "
        "probe for a candidate the step's saw but could not name, calibration.attribute.top_probes)"))


class DiagnosisStage(Out):
    """One stage of the diagnosis (calibration.replicates): how many seeds it had run, and whether the
    other seeds then ran, with the reason."""

    seeds: int
    batteries: int
    more_seeds: bool
    why: str
    top_probes: list[str] | None = Field(None, description="candidates this stage sent to be probed at their "
                                         "plausible top (calibration.attribute.top_probes)")


class LeftOutTarget(Out):
    """A measurement not compared with the runs, and why (calibration.comparable.split)."""

    test: str
    quantity: str
    condition: dict[str, float] = Field(default_factory=dict)
    reason: str
    kind: Literal["incomparable", "counted_once"] = Field(
        "incomparable", description="'incomparable': the runs' rig or resolution has no counterpart of it; "
                                    "'counted_once': the same measurement as targets already counted (a quantity "
                                    "computed from them, or the rig's own number)")


class Report(Out):
    """As stored on the iteration (GET /campaigns/{id}/iterations' ``report``)."""

    optimum: ParameterValues | None = Field(None, description=PARAMETERS)
    fixed_parameters: dict[str, Any] | None = None
    confirmation_seed: int | None = None
    confirmation_job_id: int | None = None
    confirmation_seeds: list[int] | None = None
    confirmation_job_ids: list[int | None] | None = None
    targets: list[TargetRow] = Field(default_factory=list)
    verdict: Verdict | None = Field(None, description="the one verdict (calibration.verdict)")
    meaning: str | None = None
    checks: list[Check] | None = Field(None, description="what holds and what does not; 'calibrated' needs them all")
    suspect_measurements: list[SuspectMeasurement] | None = None
    unreachable: list[str] | None = Field(None, description="responses no parameter set in the box reaches")
    confirmation_outside_interval: list[str] | None = None
    max_abs_standardised_residual: float | None = None
    lack_of_fit: LackOfFit | None = None
    tests: list[TestShare] | None = None
    trends: Trends | None = None
    conflicts: Conflicts | None = None
    suspect: bool | None = Field(None, description="conflicts or unreachable targets: diagnose even if the fit passes")
    surrogate_check: SurrogateCheck | None = None
    polish: Polish | None = None
    diagnosis: Diagnosis | None = None
    intervals: Intervals | None = Field(
        None, description="intervals on the free parameters (calibration.intervals): every noise term, widened "
                          "by a failing fit, parameters that trade named")
    diagnosis_plan: list[DiagnosisBattery] | None = Field(
        None, description="the diagnosis batteries in standard order: which effect each ran and its seed")
    diagnosis_stages: list[DiagnosisStage] | None = Field(
        None, description="one seed first, the others only where they buy power (calibration.replicates)")
    adequacy: Adequacy | None = None
    automatic: Automatic | None = None
    left_out_targets: list[LeftOutTarget] | None = Field(
        None, description="the material's measurements left out of the targets, with the reason: a quantity the "
                          "apparatus sets measured in another rig than the runs', or one that scales with the "
                          "particles' size at a coarse resolution")
    warnings: list[str] | None = Field(
        None, description="plausibility warnings of the measurements used (engine.lab.plausibility): a value "
                          "outside what granular materials measure, with the unit slip it probably is")


class ReportOut(Report):
    """GET /campaigns/{id}/report: the stored report with its campaign's fields."""

    campaign_id: int
    name: str
    material_id: int
    iteration: int
    evaluator: str
    fidelity: str
    reachable_limit: float = Field(description="the reachability above which a target is out of reach")
