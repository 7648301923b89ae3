"""Tier-A hidden-effect test bed: cases with a known missing effect, run through the whole loop.

Each case draws a true parameter set, 0, 1 or 2 hidden effects with strengths of 0.1-1 times their
plausible range, and another world's constants (``standin.Gains.perturbed``: other gains and
exponents, another saturation law). Its "measurements" are that world's values with laboratory
scatter (MEASUREMENT_SD, three replicates); the loop calibrates the unperturbed stand-in against
them. The detectability lambda of each hidden effect is ||M W delta||^2: the part of its whitened
signal the baseline parameters cannot absorb (design note 3.1), so acceptance is stated per lambda.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from engine.candidates import candidates
from engine.lab.spec import MicroParameters

from . import parameters as params_mod
from . import standin, stats
from .analysis import active_effects
from .conditions import standin_conditions
from .discrepancy import from_comparison
from .intervals import covers
from .evaluators import StandinEvaluator
from .keys import ResponseKey
from .loop import CalibrationLoop, LoopResult
from .records import Measured
from .settings import LoopSettings
from .stats import residual_maker
from .vocabulary import DiagnosisVerdict

# Laboratory scatter of one test (design note 3.1): relative sd, or absolute in degrees.
MEASUREMENT_SD = {
    ("fill", "bulk_density_kg_m3"): ("relative", 0.01),
    ("cct", "confined_modulus_pa"): ("relative", 0.08),
    ("cct", "unload_reload_modulus_pa"): ("relative", 0.08),
    ("dst", "residual_shear_stress_pa"): ("relative", 0.04),
    ("dst", "dilatancy_angle_deg"): ("absolute", 1.5),
    ("aor", "angle_of_repose_deg"): ("absolute", 1.0),
    ("anchor", "peak_pull_force_n"): ("relative", 0.06),
}
REPLICATES = 3
OPTIONS = {"dst_normal_stresses_pa": [10.5e3, 24.0e3, 38.3e3, 52.4e3],
           "cct_window_stresses_pa": [15.0e3, 30.0e3, 45.0e3, 60.0e3], "include_aor": True, "include_anchor": True}
FACTORS = [
    {"name": "particle_density_kg_m3", "low": 2300.0, "high": 2900.0},
    {"name": "friction_pp", "low": 0.2, "high": 1.0},
    {"name": "friction_pw", "low": 0.2, "high": 0.8},
    {"name": "particle_stiffness_n_per_m", "low": 1.0e6, "high": 3.0e6},
]
# true parameters are drawn from the inner part of the box (a user's box brackets the answer)
TRUE_RANGE = {"particle_density_kg_m3": (2450.0, 2750.0), "friction_pp": (0.3, 0.9),
              "friction_pw": (0.3, 0.7), "particle_stiffness_n_per_m": (1.4e6, 2.6e6)}
# Directly measured parameters (priors): particle density by pycnometer; particle-wall and
# particle-particle sliding friction by tilting tests (a plate; a bed of glued particles). Without
# the sliding-friction prior, rolling resistance and a higher mu_pp trade along a ridge (strength is
# governed by either, Estrada et al. 2008) and no data of this battery can fix the effect's strength.
PYCNOMETER_RELATIVE_SD = 0.01
TILT_TEST_SD = 0.05
PARTICLE_TILT_TEST_SD = 0.08
HERTZ_SPREAD_DECADES = 0.3
# how far the measuring world's constants stray from the model's (each gain and exponent x 1 +- this,
# and another saturation law): a model discrepancy the baseline parameters can absorb within the
# measurement noise, as a good model's would, but never the same functions (no inverse crime)
WORLD_PERTURBATION = 0.02
WORLD_SATURATION_POWER = 8.0
# Nulls and effects of another model form (issue 33): the measuring world's closed forms stray 10 % from the
# model's, the size of what two DEM engines give for the same test (E' 12 % apart, residual shear 8-34 %,
# bulk density 0.7 %: docs/diagnosis.md), beyond what the parameters can absorb within the noise. The loop
# is given a model-form discrepancy estimated as a user would: the model against *another* such world (a
# second engine's run of the same tests at the centre of the box), never against the measuring world.
FORM_PERTURBATION = 0.10
FORM_KINDS = {"form_null": ("null", True), "form_single": ("single", True), "form_null_exact": ("null", False)}


def measured_priors(truth: dict, rng: np.random.Generator, density_bias: float | None = None) -> list[dict]:
    """The directly measured parameters, as priors (pseudo-observations): particle density by
    pycnometer, particle-wall friction by a tilt test on a plate, particle-particle friction by a tilt
    test on a bed of glued particles; each the truth plus its test's scatter, drawn from ``rng`` in that
    order. ``density_bias``: the pycnometer off by this relative amount instead (tier B's nuisance).
    Tier A and tier B share it, so both worlds measure the same things."""
    rho = truth["particle_density_kg_m3"]
    draws = rng.standard_normal(3)
    density = rho * (1.0 + (PYCNOMETER_RELATIVE_SD * float(draws[0]) if density_bias is None else density_bias))
    return [{"parameter": "particle_density_kg_m3", "uncertainty": PYCNOMETER_RELATIVE_SD * rho, "value": density,
             "source": "pycnometer" if density_bias is None else f"pycnometer, {100 * density_bias:+.0f} % off"},
            {"parameter": "friction_pw", "uncertainty": TILT_TEST_SD,
             "value": truth["friction_pw"] + TILT_TEST_SD * float(draws[1]), "source": "tilt test"},
            {"parameter": "friction_pp", "uncertainty": PARTICLE_TILT_TEST_SD,
             "value": truth["friction_pp"] + PARTICLE_TILT_TEST_SD * float(draws[2]), "source": "particle tilt test"}]


def measurement_sd(record: dict) -> float | None:
    kind = MEASUREMENT_SD.get((record["test"], record["quantity"]))
    if kind is None:
        return None
    return kind[1] * abs(record["value"]) if kind[0] == "relative" else kind[1]


def target_records(values: list[dict]) -> list[dict]:
    """The quantities a case measures: every value with a laboratory scatter, E' per stress only."""
    return [v for v in values if measurement_sd(v) is not None
            and not (v["quantity"] == "confined_modulus_pa" and not v["condition"])]


@dataclass
class Case:
    seed: int
    kind: str                              # "null", "single", "two"
    effects: dict[str, float]              # candidate name -> true strength
    truth: dict[str, Any]                  # true parameter dict (effects included)
    gains: standin.Gains
    targets: list[Measured]
    priors: list[dict]
    detectability: dict[str, float] = field(default_factory=dict)
    discrepancy: list[dict] = field(default_factory=list)   # model-form discrepancy the loop is given


def _strength(name: str, u: float, rng: np.random.Generator, truth: dict) -> float:
    c = candidates()[name]
    if c.is_switch:
        ref = float(c.reference(MicroParameters.model_validate(truth)))
        return ref * 10 ** float(rng.uniform(-HERTZ_SPREAD_DECADES, HERTZ_SPREAD_DECADES))
    off = c.off_value or 0.0
    return off + u * (c.plausible_range[1] - off)


# Single-effect cases drawn for a detectability bin (kind -> lambda range): the strengths of 0.1-1 of the
# plausible range put almost every single effect at lambda >= 30, so the bins where "inconclusive" is the
# honest answer would be nearly empty; these kinds redraw (weaker strengths, other worlds) until the
# hidden effect's lambda falls in the bin, and are scored with the single effects.
LAMBDA_BINS = {"weak": (0.0, 10.0), "mid": (10.0, 30.0)}
WEAK_STRENGTH = (0.01, 0.4)
MAX_REDRAWS = 500


def make_case(seed: int, kind: str, effects: dict[str, float] | None = None) -> Case:
    """A case drawn from ``seed``; ``effects`` ({name: strength}) replaces the drawn hidden effects.

    ``kind`` "null", "single" or "two"; or a key of ``LAMBDA_BINS``: a single effect whose lambda lies in
    that bin (the case's kind is then "single")."""
    if kind in LAMBDA_BINS:
        low, high = LAMBDA_BINS[kind]
        for attempt in range(MAX_REDRAWS):
            case = _drawn_case(np.random.default_rng([seed, 20261122, 1 + attempt]), seed, "single", effects,
                               WEAK_STRENGTH)
            if all(low <= lam < high for lam in case.detectability.values()):
                return case
        raise RuntimeError(f"no draw of seed {seed} put a single effect at {low} <= lambda < {high}")
    if kind in FORM_KINDS:
        return _form_case(seed, kind, effects)
    return _drawn_case(np.random.default_rng([seed, 20261122]), seed, kind, effects, (0.1, 1.0))


def _form_case(seed: int, kind: str, effects: dict[str, float] | None) -> Case:
    """A case whose world departs from the model by FORM_PERTURBATION; with the discrepancy the loop is given
    (``FORM_KINDS[kind][1]``) or without it ("form_null_exact": the same worlds as "form_null", to show what
    the discrepancy term changes). Strong single effects only (strengths 0.3-1 of the range)."""
    base_kind, given = FORM_KINDS[kind]
    rng = np.random.default_rng([seed, 20261126])
    case = _drawn_case(rng, seed, base_kind, effects, (0.3, 1.0), perturbation=FORM_PERTURBATION)
    case.kind = kind
    if given:
        other = standin.Gains().perturbed(np.random.default_rng([seed, 20261127]), relative=FORM_PERTURBATION,
                                          saturation_power=WORLD_SATURATION_POWER)
        centre = {f["name"]: 0.5 * (f["low"] + f["high"]) for f in FACTORS}
        cond = standin_conditions(OPTIONS)

        def values(gains):
            return {ResponseKey.of(v["test"], v["quantity"], v["condition"]): v["value"]
                    for v in target_records(standin.bulk_values(centre, cond, gains))}

        case.discrepancy = [d.model_dump() for d in from_comparison(
            values(standin.Gains()), values(other),
            source="the model against another model form's run of the same tests at the box's centre")]
    return case


def _drawn_case(rng: np.random.Generator, seed: int, kind: str, effects: dict[str, float] | None,
                strength_range: tuple[float, float], perturbation: float = WORLD_PERTURBATION) -> Case:
    truth: dict[str, Any] = {name: float(rng.uniform(*TRUE_RANGE[name])) for name in TRUE_RANGE}
    names = sorted(candidates())
    count = {"null": 0, "single": 1, "two": 2}[kind]
    chosen = [names[i] for i in rng.choice(len(names), size=count, replace=False)] if count else []
    drawn = {}
    for name in chosen:
        drawn[name] = _strength(name, float(rng.uniform(*strength_range)), rng, truth)
    effects = dict(drawn if effects is None else effects)
    for name, strength in effects.items():
        truth = params_mod.apply(truth, {candidates()[name].factor: strength})
    gains = standin.Gains().perturbed(rng, relative=perturbation, saturation_power=WORLD_SATURATION_POWER)
    cond = standin_conditions(OPTIONS)
    targets = []
    for v in target_records(standin.bulk_values(truth, cond, gains)):
        sd = measurement_sd(v)
        reps = v["value"] + sd * rng.standard_normal(REPLICATES)
        targets.append(Measured(ResponseKey.of(v["test"], v["quantity"], v["condition"]), tuple(float(x) for x in reps),
                                v["unit"]))
    case = Case(seed, kind, effects, truth, gains, targets, measured_priors(truth, rng))
    case.detectability = detectability(case)
    return case


def detectability(case: Case) -> dict[str, float]:
    """lambda of each hidden effect: ||M W (f(truth) - f(truth without it))||^2 in the case's world."""
    cond = standin_conditions(OPTIONS)
    def values(params):
        return np.array([v["value"] for v in target_records(standin.bulk_values(params, cond, case.gains))])
    base = values(case.truth)
    sd = np.array([measurement_sd(v) for v in target_records(standin.bulk_values(case.truth, cond, case.gains))])
    sd = sd / math.sqrt(REPLICATES)
    cols = []
    for f in FACTORS:
        h = 1e-3 * (f["high"] - f["low"])
        up = params_mod.apply(case.truth, {f["name"]: case.truth[f["name"]] + h})
        cols.append((values(up) - base) / h * (f["high"] - f["low"]) / 2.0 / sd)
    J = np.column_stack(cols)
    # priors make rho_p and mu_w pseudo-observations: their columns absorb only within the prior sd
    prior_rows = np.zeros((3, J.shape[1]))
    rho_sd = PYCNOMETER_RELATIVE_SD * case.truth[FACTORS[0]["name"]]
    prior_rows[0, 0] = (FACTORS[0]["high"] - FACTORS[0]["low"]) / 2 / rho_sd
    prior_rows[1, 2] = (FACTORS[2]["high"] - FACTORS[2]["low"]) / 2 / TILT_TEST_SD
    prior_rows[2, 1] = (FACTORS[1]["high"] - FACTORS[1]["low"]) / 2 / PARTICLE_TILT_TEST_SD
    M = residual_maker(np.vstack([J, prior_rows]))
    out = {}
    for name in case.effects:
        c = candidates()[name]
        without = params_mod.without_effect(case.truth, name) if c.factor.startswith("effects.") else \
            params_mod.apply(case.truth, {c.factor: c.off_value})
        delta = np.concatenate([(base - values(without)) / sd, np.zeros(3)])
        out[name] = float(np.sum((M @ delta) ** 2))
    return out


DESIGN = {"type": "fractional", "generators": ["D=ABC"], "centre_runs": 3}  # the thesis's 2^(4-1), Table A.8


def loop_settings(case: Case, max_iterations: int = 3, **overrides) -> LoopSettings:
    """The loop a user would run on the case: the four factors in the thesis's half fraction, the case's
    priors, automatic mode, and the diagnosis after every iteration (its ranking is scored whether or
    not the lack-of-fit test fired, as a user asking for a diagnosis anyway sees it)."""
    settings = {"factors": [dict(f) for f in FACTORS], "design": DESIGN, "priors": case.priors, "seed": case.seed,
                "max_iterations": max_iterations, "automatic": True, "diagnose_always": True, "options": OPTIONS,
                "model_discrepancy": case.discrepancy}
    return LoopSettings.model_validate({**settings, **overrides})


def run_case(case: Case, max_iterations: int = 3, chaotic: bool = False) -> dict[str, Any]:
    """The case through the loop on the stand-in; ``chaotic``: each run's scatter drawn from its seed and parameters
    (``StandinEvaluator.chaotic``), as the DEM engine's packings diverge, instead of shared by one seed's runs."""
    evaluator = StandinEvaluator(standin_conditions(OPTIONS), chaotic=chaotic)
    result = CalibrationLoop(case.targets, evaluator, loop_settings(case, max_iterations)).run()
    return outcome(case, result, evaluator.runs)


def outcome(case: Case, result: LoopResult, runs: int) -> dict[str, Any]:
    first = result.first
    final = result.final
    diag = result.diagnosis(first.number) or {}
    ranking = diag.get("ranking") or []
    top = ranking[0] if ranking else None
    top_group = {r["effect"] for r in ranking if top is not None and top.get("alias_group") is not None
                 and r.get("alias_group") == top["alias_group"]}
    # the effects the final model keeps: an alias fitted in place of a kept effect and beaten by it was accepted
    # against the base, but is not the loop's answer
    kept = active_effects(final.parameters)
    accepted = [d["effect"] for d in result.decisions if d["accepted"] and d["effect"] in kept]
    tried = [d["effect"] for d in result.decisions]
    strengths = {}
    for name, true in case.effects.items():
        c = candidates()[name]
        est = (final.report or {}).get("optimum", {}).get(c.factor) if name in accepted else None
        off = c.off_value or 0.0
        if est is None:
            strengths[name] = None
        elif c.is_switch:
            strengths[name] = abs(math.log(est / true)) <= math.log(1.3)
        else:
            strengths[name] = abs(est - true) <= 0.3 * (true - off)
    return {"seed": case.seed, "kind": case.kind, "effects": case.effects, "detectability": case.detectability,
            "lof_fired": result.model_fails(first), "lof_p": first.report["lack_of_fit"]["p_value"],
            "final_lof_passes": not result.model_fails(final),
            "diagnosis_verdict": diag.get("verdict"), "ranking": [r["effect"] for r in ranking],
            "top_alias_group": sorted(top_group), "tried": tried, "accepted": accepted,
            "rms_before": _rms(first), "rms_after": _rms(final), "strength_within_30": strengths,
            "stop_reason": result.stop_reason, "batteries": runs,
            # an alias fitted in place of an effect that passed (calibration.automatic.settle_alias)
            "alias_refit": _refit(result),
            # candidates the step's probe saw but could not name, probed at their plausible top (attribute.top_probes)
            "top_probes": _top_probes(result),
            "top_p_holm": top.get("p_holm") if top else None,
            "coverage": _coverage(case, final)}


def _refit(result: LoopResult) -> dict[str, Any] | None:
    """{"leader", "partner", "kept", "undistinguished"} where the loop ended comparing two aliases, else None."""
    record = (result.iterations[-1].report or {}).get("automatic") or {}
    settled = record.get("alias_settled")
    if not settled:
        return None
    return {"leader": settled["leader"], "partner": settled["partner"], "kept": settled["kept_effect"],
            "undistinguished": bool(settled["undistinguished"])}


def _top_probes(result: LoopResult) -> list[dict[str, Any]]:
    """Per iteration whose diagnosis probed candidates at their plausible top: which, and what it then indicated."""
    out = []
    for it in result.iterations:
        report = it.report or {}
        probed = [name for stage in report.get("diagnosis_stages") or [] for name in stage.get("top_probes") or []]
        if probed:
            out.append({"iteration": it.number, "effects": probed,
                        "indicated": list((report.get("diagnosis") or {}).get("indicated") or [])})
    return out


def top_probe_line(outcomes: list[dict]) -> str:
    """How often a diagnosis probed a candidate at its plausible top, by kind of case, and whether it then named
    the truth (a single hidden effect) or, in a null, anything."""
    probed = [o for o in outcomes if o.get("top_probes")]
    kinds: dict[str, int] = {}
    for o in probed:
        kinds[o["kind"]] = kinds.get(o["kind"], 0) + 1
    first = [o["top_probes"][0] for o in probed]
    truth_named = sum(bool(set(p["indicated"][:1]) & set(o["effects"])) for o, p in zip(probed, first))
    return (f"top probes (a candidate the step's probe saw but could not name, probed at its plausible top): "
            f"{len(probed)} cases ({', '.join(f'{k} {n}' for k, n in sorted(kinds.items())) or 'none'}); "
            f"then indicated the hidden effect first {truth_named}, indicated something "
            f"{sum(bool(p['indicated']) for p in first)}")


def refit_line(outcomes: list[dict]) -> str:
    """What the alias refits did over the single-effect cases: how often the leader (the diagnosis's choice) and
    the model kept after the refit hold the hidden effect, and how many ended undistinguished."""
    singles = [o for o in outcomes if len(o["effects"]) == 1 and o.get("alias_refit")]
    truth = lambda o, name: name in o["effects"]  # noqa: E731
    return (f"alias refits (single effects): {len(singles)}; leader is the truth {sum(truth(o, o['alias_refit']['leader']) for o in singles)}, "
            f"kept is the truth {sum(truth(o, o['alias_refit']['kept']) for o in singles)}, "
            f"undistinguished {sum(o['alias_refit']['undistinguished'] for o in singles)}")


def _coverage(case: Case, final) -> dict[str, bool]:
    """Does the final iteration's 95 % interval hold each free parameter's true value? (Effects' strengths
    count where the effect is in the true world; an effect added wrongly has no true strength to hold.)"""
    intervals = (final.report or {}).get("intervals") or {}
    truth = {}
    for name in (intervals.get("parameters") or {}):
        value = params_mod.read(case.truth, name)
        if value is not None:
            truth[name] = float(value)
    return covers(intervals, truth)


def _rms(it) -> float:
    """Weighted RMS of the targets' standardised residuals at the iteration's confirmation."""
    return stats.weighted_rms([r["standardised_residual"] for r in it.report["targets"] if r.get("status") == "modelled"])


# ---------------------------------------------------------------------------- acceptance
MACHINE_KEYS = ("null_false_alarm", "null_wrong_effect", "single_detected", "single_rank1", "single_error_ratio",
                "single_strength_within30", "mid_rank1", "two_first_pick", "form_null_false_alarm",
                "interval_coverage")


def case_kinds(n_cases: int, per_weak_bin: int = 0, per_form_kind: int = 0) -> list[str]:
    """A sixth null, half one effect, a third two effects (design note 3.1), in a fixed order; then
    ``per_weak_bin`` single effects drawn into each of ``LAMBDA_BINS`` (the bins below lambda 30), then
    ``per_form_kind`` cases of each of ``FORM_KINDS`` (worlds of another model form)."""
    n_null = n_cases // 6
    n_two = n_cases // 3
    base = ["null"] * n_null + ["single"] * (n_cases - n_null - n_two) + ["two"] * n_two
    return (base + [b for b in LAMBDA_BINS for _ in range(per_weak_bin)]
            + [k for k in FORM_KINDS for _ in range(per_form_kind)])


def _same_or_alias(name: str, truth: set[str], o: dict) -> bool:
    group = set(o["top_alias_group"])
    return name in truth or (name in group and bool(group & truth))


@dataclass
class Row:
    case: str
    criterion: str
    key: str | None
    value: float
    n: int
    target: float
    at_most: bool

    @property
    def informational(self) -> bool:
        """A rate printed for what it tells (the design note sets no target for it)."""
        return math.isnan(self.target)

    @property
    def passes(self) -> bool:
        if self.informational:
            return True
        if self.n == 0 or math.isnan(self.value):
            return False
        return self.value <= self.target if self.at_most else self.value >= self.target


def acceptance(outcomes: list[dict]) -> list[Row]:
    """The acceptance table of design note 3.1 on a list of ``run_case`` outcomes."""
    def frac(items, pred):
        items = list(items)
        return (sum(1 for o in items if pred(o)) / len(items) if items else math.nan), len(items)

    def lam(o, name):
        return o["detectability"][name]

    null = [o for o in outcomes if o["kind"] == "null"]
    single = [o for o in outcomes if o["kind"] == "single"]
    strong = [o for o in single if lam(o, next(iter(o["effects"]))) >= 30]
    mid = [o for o in single if 10 <= lam(o, next(iter(o["effects"]))) < 30]
    weak = [o for o in single if lam(o, next(iter(o["effects"]))) < 10]
    two = [o for o in outcomes if o["kind"] == "two" and all(v >= 30 for v in o["detectability"].values())]
    form_null = [o for o in outcomes if o["kind"] == "form_null"]
    form_exact = [o for o in outcomes if o["kind"] == "form_null_exact"]
    form_single = [o for o in outcomes if o["kind"] == "form_single"
                   and lam(o, next(iter(o["effects"]))) >= 30]

    def rank1(o):
        truth = set(o["effects"])
        return bool(o["ranking"]) and _same_or_alias(o["ranking"][0], truth, o)

    def top2(o):
        return bool(set(o["ranking"][:2]) & set(o["effects"]))

    def ratio(items, final=False):
        vals = [o["rms_after"] / o["rms_before"] for o in items if o["rms_before"] > 0]
        return (float(np.median(vals)) if vals else math.nan), len(vals)

    def strength_ok(o):
        return all(v is True for v in o["strength_within_30"].values())

    def no_wrong_claim(o):
        claimed = o["diagnosis_verdict"] == DiagnosisVerdict.INDICATED and (o["top_p_holm"] or 1.0) < 0.01
        return not claimed or rank1(o)

    def no_wrong_added(o):
        truth = set(o["effects"])
        return all(_same_or_alias(name, truth, o) for name in o["accepted"])

    def claims_effect(o):
        return o["diagnosis_verdict"] == DiagnosisVerdict.INDICATED or bool(o["accepted"])

    def first_pick(o):
        return bool(o["tried"]) and _same_or_alias(o["tried"][0], set(o["effects"]), o)

    def both(o):
        truth = set(o["effects"])
        got = set(o["accepted"])
        return all(t in got or (t in o["top_alias_group"] and got & set(o["top_alias_group"])) for t in truth)

    rows = [
        Row("null", "lack-of-fit false alarm", "null_false_alarm", *frac(null, lambda o: o["lof_fired"]), 0.08, True),
        Row("null", "an effect wrongly added", "null_wrong_effect", *frac(null, lambda o: bool(o["accepted"])),
            0.10, True),
        Row("single, lambda >= 30", "detected (lack of fit fires)", "single_detected",
            *frac(strong, lambda o: o["lof_fired"]), 0.95, False),
        Row("single, lambda >= 30", "true effect rank 1 or in the top alias group", "single_rank1",
            *frac(strong, rank1), 0.90, False),
        Row("single, lambda >= 30", "median weighted RMS after / before", "single_error_ratio", *ratio(strong),
            0.5, True),
        Row("single, lambda >= 30", "post-fit lack of fit passes", None, *frac(strong, lambda o: o["final_lof_passes"]),
            0.80, False),
        Row("single, lambda >= 30", "strength within 30 % of the truth", "single_strength_within30",
            *frac(strong, strength_ok), 0.80, False),
        Row("single, 10 <= lambda < 30", "rank 1 (or top alias group)", "mid_rank1", *frac(mid, rank1), 0.70, False),
        Row("single, 10 <= lambda < 30", "top 2", None, *frac(mid, top2), 0.90, False),
        Row("single, 10 <= lambda < 30", "no wrong effect added", None, *frac(mid, no_wrong_added), 0.90, False),
        Row("single, lambda < 10", "no wrong claim at p < 0.01", None, *frac(weak, no_wrong_claim), 0.90, False),
        Row("single, lambda < 10", "no wrong effect added", None, *frac(weak, no_wrong_added), 0.90, False),
        Row("single, lambda < 10", "true effect in the top two", None, *frac(weak, top2), math.nan, False),
        Row("two, both lambda >= 30", "first pick one of the pair", "two_first_pick", *frac(two, first_pick),
            0.85, False),
        Row("two, both lambda >= 30", "both recovered within 3 iterations", None, *frac(two, both), 0.60, False),
        Row("two, both lambda >= 30", "median weighted RMS after / before", None, *ratio(two), 0.3, True),
        # issue 33's goal for the 95 % intervals (calibration.intervals): the truth inside in >= 90 % of the
        # (case, parameter) pairs, model-form departures included (the intervals carry the shift a passing lack
        # of fit cannot see)
        Row("every case", "95 % intervals holding the truth", "interval_coverage",
            *_coverage_rate(outcomes), 0.90, False),
        Row("null, other form, discrepancy", "effect indicated or added", "form_null_false_alarm",
            *frac(form_null, claims_effect), 0.10, True),
        Row("null, other form, discrepancy", "lack-of-fit fires", None, *frac(form_null, lambda o: o["lof_fired"]),
            math.nan, True),
        Row("null, other form, none given", "lack-of-fit fires", None, *frac(form_exact, lambda o: o["lof_fired"]),
            math.nan, True),
        Row("null, other form, none given", "effect indicated or added", None, *frac(form_exact, claims_effect),
            math.nan, True),
        Row("single >= 30, other form", "lack-of-fit fires", None, *frac(form_single, lambda o: o["lof_fired"]),
            math.nan, False),
        Row("single >= 30, other form", "true effect added (or its alias)", None,
            *frac(form_single, lambda o: bool(o["accepted"]) and no_wrong_added(o)), math.nan, False),
        Row("single >= 30, other form", "no wrong effect added", None, *frac(form_single, no_wrong_added),
            0.90, False),
    ]
    return rows


def _coverage_rate(outcomes: list[dict]) -> tuple[float, int]:
    pairs = [held for o in outcomes for held in (o.get("coverage") or {}).values()]
    return (sum(pairs) / len(pairs) if pairs else math.nan), len(pairs)


def table_text(rows: list[Row]) -> str:
    lines = [f"{'case':<28}{'criterion':<48}{'n':>5}{'value':>9}{'target':>10}  ok"]
    for r in rows:
        target = "-" if r.informational else ("<= " if r.at_most else ">= ") + f"{r.target:g}"
        ok = "-" if r.informational else "yes" if r.passes else "NO"
        lines.append(f"{r.case:<28}{r.criterion:<48}{r.n:>5}{r.value:>9.3f}{target:>10}  {ok}")
    return "\n".join(lines)


def machine_line(rows: list[Row]) -> str:
    by_key = {r.key: r.value for r in rows if r.key}
    return " ".join(f"{k}={by_key[k]:.3f}" for k in MACHINE_KEYS)
