"""The diagnosis of an iteration: which candidate effect explains the misfit the fitted parameters cannot
absorb (calibration.attribute.Attribution.to_dict, with the lack of fit, seeds and batteries of
calibration.analysis.diagnose)."""
from __future__ import annotations

from pydantic import Field

from calibration.vocabulary import DiagnosisVerdict, Probe
from service.api.responses.common import LackOfFit, Out


class ProbeScore(Out):
    """One probe of a candidate's strength and the score its signature got."""

    probe: Probe
    strength_probed: float | None = Field(description="the strength the probe's batteries ran at, in its unit")
    lm: float
    explained: float = Field(description="share of the misfit this probe's signature explains, 0..1")
    strength: float | None = Field(description="the strength this probe's secant asks for")


class RankedEffect(Out):
    """One candidate effect's one-sided score test against the residuals."""

    effect: str = Field(description="the candidate's registry name")
    title: str
    factor: str = Field(description="the micro-parameter path its strength is")
    unit: str = Field(description="the strength's unit")
    lm: float | None = Field(description="Lagrange-multiplier score statistic")
    p_value: float | None
    p_holm: float | None = Field(description="p after Holm over the candidates")
    explained: float | None = Field(description="share of the misfit the effect explains, 0..1, its signature's "
                                    "own noise taken out (calibration.attribute.explained_share)")
    explained_observed: float | None = Field(None, description="the same share as the noisy signature shows it "
                                             "(absent in diagnoses made before session 39)")
    gamma: float | None = Field(description="the score's step along the signature")
    strength: float | None = Field(description="the strength the data ask for, in its unit: off + gamma, gamma "
                                   "divided by its signature's attenuation (calibration.attribute.attenuation; "
                                   "diagnoses made before session 40 read gamma as it stands)")
    fraction_of_switch: float | None = Field(description="a switch-type effect: the fraction of its matched strength")
    plausible_range: list[float] = Field(description="[low, high], in its unit")
    proposed_range: list[float] | None = Field(None, description="[low, high] adding this effect gets by default "
                                               "(calibration.decisions.effect_range); null: no matched strength")
    plausible: bool
    significant: bool = Field(description="p_holm below alpha")
    alias_group: int | None = Field(description="the alias group it belongs to, from 1")
    signature_noise: float | None = Field(0.0, description=(
        "share of its projected signature's squared length the simulator's scatter accounts for in expectation "
        "(calibration.attribute.noise_share); the score is attenuated by about 1 - this; 0: not known; null: the "
        "projected signature has no length (the baseline parameters absorb all of it), so there is no score"))
    probe: Probe = Field(Probe.STEP, description="the probe the score is read from: 'step' (the secant step) or 'top' "
                       "(the plausible top, where both ran and it scored higher; p then Bonferroni over both)")
    probes: list[ProbeScore] = Field(default_factory=list, description="each probe's score, where more than one ran")


class _Visibility(Out):
    """What ``calibration.unseen`` says of one candidate's visibility in these measurements."""

    effect: str
    title: str
    lm_needed: float = Field(description="the noncentrality at which Holm's first step flags it with `power`")
    power: float
    signature_noise: float | None = Field(description="share of its probe's projected length that is noise")
    measure: list[str] = Field(description="what would show it or decide it")


class UnseenEffect(_Visibility):
    """A candidate these measurements could not see at any plausible strength (calibration.unseen)."""

    lm_at_top: float = Field(description="the score test's noncentrality at the top of its plausible range "
                                         "(the full switch for a law that replaces the baseline's)")
    smallest_seen: float | None = Field(description="the smallest strength that would be seen, in its unit "
                                                    "(a switch: the fraction of it); null: none would")


class UndeterminedEffect(_Visibility):
    """A candidate whose probe was too noisy to say whether these measurements would see it (calibration.unseen)."""

    lm_at_top_low: float = Field(description="noncentrality at the plausible top on the lower bound of its "
                                             "signature's length (the probe's scatter taken away)")
    lm_at_top_high: float = Field(description="the same on the upper bound (the scatter added)")


class Separator(Out):
    effects: list[str] = Field(description="the two effects")
    cos: float = Field(description="cosine of their projected signatures")
    separation_z: float | None = Field(
        None, description="how far (standard deviations) the data prefer the leader, where below 1.645 joined "
                          "them; absent when their signatures alone are collinear enough (abs(cos) > 0.9)")
    separating_measurement: str = Field(description="the measurement that tells them apart best")


class AliasGroup(Out):
    group: int
    effects: list[str]
    separators: list[Separator]
    message: str


class Fingerprints(Out):
    """Signs of the change each effect makes, and the signs the measurements show."""

    columns: list[str]
    observed: dict[str, str] = Field(description="per column: '+', '-', '0' or '' (not measured)")
    effects: dict[str, dict[str, str]] = Field(description="per effect, per column: the sign it leaves")


class DirectedTest(Out):
    """The max-T score test over the candidates against its simulated null."""

    lm: float | None
    p_value: float | None
    n_candidates: int


class DiagnosisAdequacy(Out):
    p_value: float | None = Field(description="Holm over the omnibus lack of fit and the directed test")
    fails: bool
    about: str


class Diagnosis(Out):
    """As stored in the report's ``diagnosis``."""

    simulator_share: float | None = Field(None, description="median over targets of 2 s_sim^2 over the residual's "
                                          "variance: a one-seed signature's noise (calibration.replicates)")

    verdict: DiagnosisVerdict = Field(description="effect indicated, inconclusive, no physical match, suspect "
                                                  "measurement or no misfit")
    attribution_verdict: DiagnosisVerdict | None = Field(
        None, description="the ranking's own verdict, where a suspect measurement overrides it")
    message: str
    ranking: list[RankedEffect] = Field(description="plausible effects first, then by LM")
    indicated: list[str] = Field(description="the effects to try, in ranking order")
    alias_groups: list[AliasGroup]
    fingerprints: Fingerprints
    measure_next: list[str]
    alpha: float
    min_explained: float = Field(description="share of the misfit an indicated effect must explain")
    critical_lm: float | None = Field(description="LM a single effect needs to clear Holm's first step")
    unseen: list[UnseenEffect] = Field(
        default_factory=list, description="candidates these measurements could not see at any plausible strength: "
                                          "a 'no misfit' does not speak for or against them")
    undetermined: list[UndeterminedEffect] = Field(
        default_factory=list, description="candidates whose probes were too noisy to say whether these measurements "
                                          "would see them: a 'no misfit' does not rule them out")
    directed: DirectedTest | None
    adequacy: DiagnosisAdequacy
    lack_of_fit: LackOfFit = Field(description="over every battery at the optimum together")
    seeds: list[int] = Field(description="the confirmation's and the diagnosis batteries' seeds")
    batteries: int = Field(description="diagnosis batteries run")


class DiagnosisOut(Diagnosis):
    """GET /campaigns/{id}/diagnosis."""

    campaign_id: int
    iteration: int
