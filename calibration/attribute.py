"""Which physical effect is missing: orthogonalised one-sided score tests, alias groups, fingerprints.

For each candidate e (``engine.candidates``) the battery ran at the optimum with e switched on, with
the seeds of the baseline runs there (common random numbers). Its whitened signature
s_e = (f(theta*, e on) - f(theta*, off)) / sd / step says what e does; what the free baseline
parameters can absorb is projected out (M, from the fitted models' sensitivities), and a one-sided
score test asks how much of the remaining misfit e explains (``stats.score_test``).

A signature is a secant from "off" to the candidate's step. Where the step's probe saw an effect (Holm-significant)
but could not name it, the candidate is probed again at its plausible top (``top_probes``): a strong effect's
response can bend beyond the step. Its score is then read from the better probe, its p Bonferroni over the two,
and the directed test takes its maximum over every probe's signature.

Effects whose projected signatures are nearly collinear (|cos| > ALIAS_COS) cannot be told apart by
these measurements: they form an alias group, reported with the measurement where their
signatures differ most, i.e. the one that would separate them. Less collinear effects can still be
indistinguishable on these data: when the leading candidate's score is not significantly above a
rival's (``separation_z``), the two join one group too, since naming either alone would be a claim the
measurements do not support.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from engine.effects.base import FINGERPRINT_COLUMNS, Candidate

from . import stats
from . import unseen as unseen_mod
from .keys import find
from .localise import ALPHA, Localisation
from .vocabulary import DiagnosisVerdict, Probe

ALIAS_COS = 0.9
# One-sided 5 % point of the normal: the leading candidate is told apart from a rival only when its
# projected score exceeds the rival's by this many standard deviations of their difference.
SEPARATION_Z = 1.645
# An effect must explain at least this share of the misfit left after the baseline parameters
# have absorbed what they can, or it is not "the" missing effect, whatever its p-value.
MIN_EXPLAINED = 0.3
# The signature's noise share (``noise_share``) up to which the share it explains is corrected for the
# attenuation that noise causes (``explained_share``); beyond it the correction would more than double a length
# that is mostly noise, and the probe is read as it stands (``calibration.unseen`` names it undetermined).
MAX_CORRECTED_NOISE = 0.5
# A linear signature of a saturating effect underestimates strong effects: strengths up to this
# multiple of the plausible range's top are still called plausible.
PLAUSIBLE_SLACK = 2.0


@dataclass
class Signature:
    candidate: Candidate
    vector: np.ndarray            # whitened, per unit strength (rows: targets then priors)
    step: float                   # strength change the battery applied
    reference: float | None = None  # switch-type: the strength switched on
    # variance of each row of ``vector`` that the simulator's scatter puts there (signature_noise_var);
    # None: not known (a deterministic evaluator, or a caller that does not say)
    noise_var: np.ndarray | None = None
    # where the strength was probed: STEP (the candidate's secant step) or TOP (its plausible top, top_probes)
    probe: str = Probe.STEP.value


# the probes' names as the stored plan and the report hold them (calibration.vocabulary.Probe)
STEP, TOP = Probe.STEP.value, Probe.TOP.value


# signature batteries run at the confirmation seeds plus this (modulo the largest seed)
SIGNATURE_SEED_OFFSET = 500_009
SEED_MAX = 2**31 - 1


def signature_seeds(confirmation_seeds) -> list[int]:
    """Seeds of the diagnosis batteries (a baseline at the optimum and each candidate), not the
    confirmation's. On the DEM engine a candidate's battery and the optimum's at one seed drift apart
    (the trajectories are chaotic), so a signature taken against the confirmation batteries would carry
    their noise, which the residuals carry with the opposite sign: every candidate then seems to explain
    the residual (the tier-B null: four unrelated effects each "explained" 30-74 % of its misfit), and
    the directed test loses its size. Against a baseline of its own, at seeds of its own, a signature's
    noise is independent of the residuals, as the directed test's null assumes, and each candidate is
    still paired with the baseline at the same seed (common random numbers)."""
    return [(int(s) + SIGNATURE_SEED_OFFSET) % SEED_MAX for s in confirmation_seeds]


def signature_vector(res, on: list[dict], base: list[dict], step: float) -> np.ndarray:
    """A candidate's signature on the residual rows of ``res`` (calibrate.Residuals): the mean of its
    batteries minus the mean of the baseline's at the same seeds (``on``, ``base``: run_values dicts,
    one per seed), over each row's sd and the strength step; zero where a battery lacks the target,
    and on the prior rows (an effect does not move a directly measured parameter)."""
    diff = []
    for i, key in enumerate(res.keys):
        k_on, k_base = find(on[0].keys(), key), find(base[0].keys(), key)
        if k_on is None or k_base is None:
            diff.append(0.0)
            continue
        mean_on = float(np.mean([v[k_on] for v in on]))
        diff.append((mean_on - float(np.mean([v[k_base] for v in base]))) / res.sd[i] / step)
    return np.concatenate([diff, np.zeros(len(res.prior_names))])


def signature_noise_var(res, simulator_sd: dict, n_seeds: int, step: float) -> np.ndarray:
    """Per row of a signature (``signature_vector``'s units), the variance the simulator's scatter gives it:
    the signature is a difference of two means of ``n_seeds`` batteries, each of sd ``simulator_sd[key]``,
    over the row's sd and the step, so 2 s_sim^2 / (n_seeds sd^2 step^2); zero where the simulator's sd is
    unknown and on the prior rows."""
    out = []
    for i, key in enumerate(res.keys):
        sd_sim = simulator_sd.get(key)
        out.append(0.0 if not sd_sim or n_seeds < 1 else
                   2.0 * sd_sim ** 2 / (n_seeds * float(res.sd[i]) ** 2 * step ** 2))
    return np.concatenate([out, np.zeros(len(res.prior_names))])


def explained_share(explained: float, noise: float) -> float:
    """The share of the misfit an effect explains, its signature's own noise taken out: LM / |r~|^2 divided by
    (1 - ``noise``), ``noise`` the signature's ``noise_share``, where that is below MAX_CORRECTED_NOISE.
    Why: a signature measured with noise explains less of the misfit than the effect does, in expectation by the
    factor 1 - share (errors in variables: |M s|^2 carries the noise, u.r does not). On the engine, where a
    probe's batteries share no scatter with its baseline's, this dragged a strong effect below MIN_EXPLAINED:
    tier A's case 157 on a chaotic stand-in (Hertz, lambda 523) explained 29 % at a noise share of 0.26 (39 %
    corrected) and the loop ended "inconclusive" (docs/diagnosis.md, Tier A, session 39)."""
    reliability = attenuation(noise)
    return explained if reliability == 1.0 else min(1.0, explained / reliability)


def attenuation(noise: float) -> float:
    """The factor a signature's noise share ``noise`` shrinks its score's share and step by in expectation,
    1 - ``noise`` (the reliability ratio of a regressor measured with error; Fuller 1987, section 1.1), where the
    share is below MAX_CORRECTED_NOISE; 1 otherwise (not known, or mostly noise and read as it stands).
    Why the step too: gamma = s.r / |s|^2 with s = t + e keeps the true numerator while |s|^2 carries E|e|^2, so
    the strength the diagnosis reads (and the range an added effect gets from it) falls short by the same factor."""
    return 1.0 - noise if 0.0 < noise < MAX_CORRECTED_NOISE else 1.0


def noise_share(M: np.ndarray, signature: np.ndarray, noise_var: np.ndarray | None) -> float:
    """The share of a projected signature's squared length the simulator's noise accounts for in
    expectation, E|M e|^2 / |M s|^2 with e ~ N(0, diag(noise_var)) (trace(M D M^T) = sum_j D_j |M_:j|^2).

    Why: noise in a signature attenuates its score the way a regressor measured with error does: with
    s = true + e, u.r keeps the true projection's numerator while |M s| grows, so LM_observed ~
    LM_true (1 - share). A share near 1 says the probe measured the packing's noise, not the effect."""
    if noise_var is None:
        return 0.0
    projected = M @ np.asarray(signature, float)
    length2 = float(projected @ projected)
    noise = float(np.sum(np.asarray(noise_var, float) * np.sum(M * M, axis=0)))
    if length2 <= 1e-300:
        return math.inf if noise > 0 else 0.0
    return noise / length2


@dataclass
class Ranked:
    name: str
    title: str
    score: stats.Score
    p_holm: float
    strength: float | None        # estimated strength in the parameter's unit (None: switch-type)
    fraction: float | None        # switch-type: estimated share of the full switch
    plausible: bool
    alias_group: int | None = None
    projected: np.ndarray | None = field(default=None, repr=False)
    signature_noise: float = 0.0  # noise_share of its signature (0: not known)
    probe: str = STEP             # the probe the score is read from (the better one where both ran)
    probes: list[dict] = field(default_factory=list)  # each probe's score where more than one ran

    @property
    def explained(self) -> float:
        """The share of the misfit it explains, its signature's noise taken out (``explained_share``)."""
        return explained_share(self.score.explained, self.signature_noise)

    def to_dict(self, candidate: Candidate) -> dict[str, Any]:
        return {"effect": self.name, "title": self.title, "factor": candidate.factor, "unit": candidate.unit,
                "lm": self.score.lm, "p_value": self.score.p_value, "p_holm": self.p_holm,
                "explained": self.explained, "explained_observed": self.score.explained, "gamma": self.score.gamma,
                "strength": self.strength, "fraction_of_switch": self.fraction,
                "plausible_range": list(candidate.plausible_range), "plausible": self.plausible,
                "proposed_range": _proposed_range(candidate, self.strength),
                "significant": bool(self.p_holm < ALPHA), "alias_group": self.alias_group,
                "signature_noise": self.signature_noise, "probe": self.probe, "probes": self.probes}


def _proposed_range(candidate: Candidate, strength: float | None) -> list[float] | None:
    """The strength range adding this effect would get by default (``calibration.decisions.effect_range``,
    as ``POST .../iterations {"add_effect"}`` and the automatic mode use it), for a form to start from:
    a range from "off" keeps the model without the effect inside the next design (its low face)."""
    from calibration.decisions import effect_range

    try:
        low, high, _ = effect_range(candidate, strength, strength)
    except ValueError:  # a switch-type effect with no matched strength
        return None
    return [float(low), float(high)]


@dataclass
class Attribution:
    ranking: list[Ranked]
    alias_groups: list[dict]
    fingerprints: dict[str, Any]
    verdict: DiagnosisVerdict
    message: str
    measure_next: list[str]
    candidates: dict[str, Candidate]
    directed: stats.DirectedTest | None = None   # the max-T score test over the candidates
    adequacy_p: float | None = None               # Holm over the omnibus lack of fit and ``directed``
    unseen: list[dict] = field(default_factory=list)  # candidates these measurements could not see (unseen.py)
    undetermined: list[dict] = field(default_factory=list)  # candidates whose probes were too noisy to tell

    @property
    def fails(self) -> bool:
        """The model misses the measurements, by the omnibus or the directed test (Holm)."""
        return self.adequacy_p is not None and self.adequacy_p < ALPHA

    @property
    def best(self) -> Ranked | None:
        return self.ranking[0] if self.ranking else None

    def indicated(self) -> list[str]:
        """The effects to try, in ranking order: those significant after Holm, with a plausible
        strength, explaining at least MIN_EXPLAINED of the remaining misfit."""
        return [r.name for r in self.ranking if r.p_holm < ALPHA and r.plausible and r.explained >= MIN_EXPLAINED]

    def to_dict(self) -> dict[str, Any]:
        return {"verdict": self.verdict, "message": self.message,
                "ranking": [r.to_dict(self.candidates[r.name]) for r in self.ranking],
                "indicated": self.indicated(),
                "alias_groups": self.alias_groups, "fingerprints": self.fingerprints,
                "measure_next": self.measure_next, "alpha": ALPHA, "min_explained": MIN_EXPLAINED,
                "critical_lm": unseen_mod.critical_lm(ALPHA, len(self.ranking)), "unseen": self.unseen,
                "undetermined": self.undetermined,
                "directed": None if self.directed is None else self.directed.to_dict(),
                "adequacy": {"p_value": self.adequacy_p, "fails": self.fails,
                             "about": "Holm over the omnibus lack of fit and the directed test (the largest "
                                      "candidate score against its simulated null): the model misses the "
                                      "measurements when either p is below alpha / 2"}}


def _plausible(candidate: Candidate, strength: float | None, fraction: float | None) -> bool:
    if fraction is not None:
        return 0.25 <= fraction <= PLAUSIBLE_SLACK
    low, high = candidate.plausible_range
    off = candidate.off_value or 0.0
    return strength is not None and off < strength <= off + PLAUSIBLE_SLACK * (high - off)


def observed_fingerprint(loc: Localisation) -> dict[str, str]:
    """Signs the measurements show, in the fingerprint's columns (blank where not measured)."""
    def sign(values, limit=1.0):
        if not values:
            return ""
        z = float(np.mean(values)) * math.sqrt(len(values))
        return "+" if z > limit else "-" if z < -limit else "0"

    rows = [r for r in loc.rows if r["test"] != "prior"]
    pick = lambda test, quantity: [r["standardised_residual"] for r in rows  # noqa: E731
                                   if r["test"] == test and r["quantity"] == quantity]
    out = {"bulk_density": sign(pick("fill", "bulk_density_kg_m3")),
           "modulus_level": sign(pick("cct", "confined_modulus_pa")),
           "friction_angle": sign(pick("dst", "residual_shear_stress_pa")),
           "dilatancy": sign(pick("dst", "dilatancy_angle_deg")),
           "angle_of_repose": sign(pick("aor", "angle_of_repose_deg")),
           "pull_force": sign(pick("anchor", "peak_pull_force_n"))}
    t = loc.trends.get("modulus_log_slope")
    out["modulus_slope"] = "" if t is None else ("+" if t["significant"] and t["slope"] > 0 else
                                                 "-" if t["significant"] else "0")
    t = loc.trends.get("shear_stress")
    out["cohesion"] = "" if t is None else ("+" if t["significant_intercept"] and t["intercept"] > 0 else
                                            "-" if t["significant_intercept"] else "0")
    return {c: out.get(c, "") for c in FINGERPRINT_COLUMNS}


def separation_z(lm_lead: float, lm_rival: float, cos: float) -> float:
    """How many standard deviations the leading candidate's projected score exceeds a rival's.

    With whitened residuals r ~ N(mu, I) and unit projected signatures u_a, u_b (u_a . u_b = cos), the
    two scores u.r have unit variance and covariance cos, so sqrt(LM_a) - sqrt(LM_b) = (u_a - u_b).r has
    standard deviation sqrt(2 (1 - cos)). A large z says the data prefer the lead whichever of the two is
    true; a small one says either could have produced these residuals."""
    spread = math.sqrt(max(2.0 * (1.0 - cos), 0.0))
    gap = math.sqrt(max(lm_lead, 0.0)) - math.sqrt(max(lm_rival, 0.0))
    return math.inf if spread <= 1e-12 and gap > 0 else (gap / spread if spread > 1e-12 else 0.0)


def _not_separated(ranked: list[Ranked], cos: np.ndarray) -> list[tuple[int, int, float]]:
    """(lead, rival, z) for the rivals the leading candidate (ranked[0]) is not told apart from: both
    explain the misfit in the direction the effect acts (gamma > 0) and z < SEPARATION_Z."""
    if not ranked or ranked[0].score.gamma <= 0 or ranked[0].score.lm <= 0:
        return []
    out = []
    for b in range(1, len(ranked)):
        if ranked[b].score.gamma <= 0 or cos[0, b] <= 0:
            continue
        z = separation_z(ranked[0].score.lm, ranked[b].score.lm, cos[0, b])
        if z < SEPARATION_Z:
            out.append((0, b, z))
    return out


def _alias_groups(ranked: list[Ranked], labels: list[str]) -> list[dict]:
    n = len(ranked)
    unit = []
    for r in ranked:
        v = r.projected
        norm = float(np.linalg.norm(v)) if v is not None else 0.0
        unit.append(v / norm if norm > 0 else None)
    parent = list(range(n))

    def root(i):
        while parent[i] != i:
            i = parent[i]
        return i

    cos = np.zeros((n, n))
    for a in range(n):
        for b in range(a + 1, n):
            if unit[a] is None or unit[b] is None:
                continue
            cos[a, b] = cos[b, a] = float(unit[a] @ unit[b])
            if abs(cos[a, b]) > ALIAS_COS:
                parent[root(b)] = root(a)
    close = {(a, b): z for a, b, z in _not_separated(ranked, cos)}
    for a, b in close:
        parent[root(b)] = root(a)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(i)
    out = []
    for members in groups.values():
        if len(members) < 2:
            continue
        gid = len(out) + 1
        separators = []
        for x in range(len(members)):
            for y in range(x + 1, len(members)):
                a, b = members[x], members[y]
                diff = unit[a] - np.sign(cos[a, b]) * unit[b]
                k = int(np.argmax(np.abs(diff[:len(labels)])))
                z = close.get((a, b), close.get((b, a)))
                separators.append({"effects": [ranked[a].name, ranked[b].name], "cos": cos[a, b],
                                   "separation_z": z, "separating_measurement": labels[k]})
        for i in members:
            ranked[i].alias_group = gid
        out.append({"group": gid, "effects": [ranked[i].name for i in members], "separators": separators,
                    "message": "these effects change the measured quantities in nearly the same proportions, "
                               "or explain these residuals about equally well; "
                               "refitting each as a factor, or measuring "
                               + " / ".join(sorted({s["separating_measurement"] for s in separators}))
                               + " more precisely, tells them apart"})
    return out


def attribute(loc: Localisation, r: np.ndarray, M: np.ndarray, signatures: list[Signature],
              labels: list[str], room: tuple[list[str], float] = ((), 0.0)) -> Attribution:
    """Rank the candidates; ``labels`` name the target rows (for the separating measurement). The
    directed test runs against the localisation's own null draws, and the verdict is judged on the
    localisation with that test (``Localisation.with_directed``), as the caller's iteration then is.
    ``room``: (parameters pinned on a box edge short of their typical range, which ``M`` counts as
    absorbing; the lack-of-fit p of what ``M`` leaves, NaN when nothing is left); when what they leave
    lies within the noise the verdict says a wider box comes first."""
    candidates = {s.candidate.name: s.candidate for s in signatures}
    # every probe's signature enters the directed test's maximum, so its simulated null prices the extra look
    directed = stats.directed_test(r, M, [s.vector for s in signatures], loc.null_draws)
    loc = loc.with_directed(directed)
    ranked = []
    for name, c in candidates.items():
        probes = [(sig, stats.score_test(r, sig.vector, M)) for sig in signatures if sig.candidate.name == name]
        sig, score = max(probes, key=lambda pair: pair[1].lm)
        if len(probes) > 1:
            # the better of k probes: Bonferroni over them, so the candidate's p keeps its size
            score = stats.Score(score.gamma, score.lm, score.explained, min(1.0, len(probes) * score.p_value))
        # the strength from the score's step, its signature's noise taken out (``attenuation``)
        noise = noise_share(M, sig.vector, sig.noise_var)
        gamma = score.gamma / attenuation(noise)
        if c.is_switch:
            strength, fraction = (sig.reference if gamma > 0 else None), gamma
        else:
            strength, fraction = (c.off_value or 0.0) + gamma, None
        detail = [] if len(probes) == 1 else [
            {"probe": s.probe, "strength_probed": (c.off_value or 0.0) + s.step if not c.is_switch else s.reference,
             "lm": sc.lm, "explained": sc.explained,
             "strength": (c.off_value or 0.0) + sc.gamma / attenuation(noise_share(M, s.vector, s.noise_var))
             if not c.is_switch else None}
            for s, sc in probes]
        ranked.append(Ranked(c.name, c.title, score, 1.0, strength, fraction,
                             _plausible(c, strength, fraction), projected=M @ sig.vector,
                             signature_noise=noise, probe=sig.probe, probes=detail))
    for row, adj in zip(ranked, stats.holm([x.score.p_value for x in ranked])):
        row.p_holm = float(adj)
    ranked.sort(key=lambda x: (-(x.plausible and x.score.gamma > 0), -x.score.lm))
    groups = _alias_groups(ranked, labels)
    fingerprints = {"columns": list(FINGERPRINT_COLUMNS), "observed": observed_fingerprint(loc),
                    "effects": {c.name: {col: c.fingerprint.get(col, "0") for col in FINGERPRINT_COLUMNS}
                                for c in candidates.values()}}
    verdict, message, measure_next = _verdict(loc, ranked, groups, labels, r, M, room)
    steps = [s for s in signatures if s.probe == STEP]
    blind = unseen_mod.unseen(steps, M, ALPHA, set(labels))
    open_ = unseen_mod.undetermined(steps, M, ALPHA, set(labels))
    if verdict == DiagnosisVerdict.NO_MISFIT and (blind or open_):
        # "no misfit" does not speak for an effect the measurements could not have seen, nor for one whose probe
        # was too noisy to tell: say which, and what would
        message += "".join("; " + text for text in (unseen_mod.message(blind), unseen_mod.undetermined_message(open_))
                           if text)
        measure_next = list(dict.fromkeys(m for row in blind + open_ for m in row["measure"]))
    return Attribution(ranked, groups, fingerprints, verdict, message, measure_next, candidates, directed,
                       loc.adequacy_p, blind, open_)


def _verdict(loc: Localisation, ranked: list[Ranked], groups: list[dict], labels, r, M, room=((), 0.0)):
    rt = M @ r
    worst = [labels[i] for i in np.argsort(-np.abs(rt[:len(labels)]))[:3]]
    if loc.lack_of_fit.dof <= 0:
        return (DiagnosisVerdict.INCONCLUSIVE, "as many free parameters as measured values: every misfit can be absorbed, so "
                "none can be attributed; measure more (each shear load, E' at several stresses, dilatancy, "
                "the angle of repose) or fix parameters measured directly", [])
    if not loc.fails:
        return (DiagnosisVerdict.NO_MISFIT, "the model agrees with the measurements within their noise; no effect is needed",
                [])
    names, left_p = room
    if names and not left_p < ALPHA:  # NaN (nothing left) or within the noise
        return (DiagnosisVerdict.INCONCLUSIVE,
                f"the misfit lies along what a wider box for {', '.join(names)} would absorb (pinned on an edge "
                "short of its typical range): widen that range before adding physics", [])
    good = [x for x in ranked if x.p_holm < ALPHA and x.plausible and x.explained >= MIN_EXPLAINED]
    if good:
        best = good[0]
        group = next((g for g in groups if best.name in g["effects"]), None)
        text = (f"{best.title} ({best.name}) explains {100 * best.explained:.0f} % of the misfit the "
                f"baseline parameters cannot absorb (LM {best.score.lm:.1f}, Holm p {best.p_holm:.2g})")
        if best.probe == TOP:
            shares = ", ".join("{:.0f} % probed at {:.3g}".format(100 * d["explained"], d["strength_probed"])
                               for d in best.probes)
            text += f", read from its probe at the plausible top: its response is not linear in strength ({shares})"
        if group is not None:
            others = [e for e in group["effects"] if e != best.name]
            text += f"; it is aliased with {', '.join(others)}"
        nxt = sorted({s["separating_measurement"] for s in group["separators"]}) if group else []
        return DiagnosisVerdict.INDICATED, text, nxt
    strong = [x for x in ranked if x.p_holm < ALPHA and x.explained >= MIN_EXPLAINED]
    best_share = max((x.explained for x in ranked), default=0.0)
    partly = [x for x in ranked if x.p_holm < ALPHA and x.score.gamma > 0]
    partial = ("; candidates that fit part of it: " + ", ".join(
        f"{x.name} {100 * x.explained:.0f} %" for x in partly)) if partly else ""
    if loc.lack_of_fit.p_value < 1e-3 and best_share < MIN_EXPLAINED:
        return (DiagnosisVerdict.NO_MATCH,
                "the misfit matches no candidate effect's signature (best explains "
                f"{100 * best_share:.0f} %){partial}; it sits in {', '.join(worst)}: check those measurements "
                "(units, condition, a physically impossible value) or the test set-up before adding physics",
                worst)
    if strong and not any(x.plausible for x in strong):
        return (DiagnosisVerdict.NO_MATCH,
                f"only implausible strengths would explain the misfit ({strong[0].name} at "
                f"{strong[0].strength if strong[0].strength is not None else strong[0].fraction:.3g}); "
                f"it sits in {', '.join(worst)}: check those measurements first", worst)
    return (DiagnosisVerdict.INCONCLUSIVE,
            f"the model misses the measurements, but no candidate effect explains enough of it to be named{partial}; "
            f"the misfit sits in {', '.join(worst)}: more replicates there, or a measurement at another "
            "stress, would sharpen the diagnosis", worst)


def top_probes(diagnosis: dict[str, Any], probed: set[str] = frozenset()) -> list[str]:
    """The candidates to probe again at their plausible top (``Candidate.top_step``), in ranking order.

    Why: a signature is a secant from "off" to one step; a strong effect's response can bend beyond it (an
    adhesion that outweighs the particles' weight loosens the pour, which a weak one does not), so the step's
    direction misses the misfit of an effect several steps strong. On DEM's cohesion_strong (Gamma 180 J/m2,
    step 60) the step's signature explained 18 % of the misfit and the verdict was "no physical match"; the
    same batteries at 200 J/m2 explained 45 % (session 31, docs/diagnosis.md). The second probe runs only where
    the first saw the effect (Holm-significant, positive strength) but could not name it: the model misses the
    measurements and no candidate is indicated. ``probed``: candidates already probed at their top."""
    from engine.candidates import candidates

    if diagnosis.get("indicated") or not (diagnosis.get("adequacy") or {}).get("fails"):
        return []
    table = candidates()
    return [row["effect"] for row in diagnosis.get("ranking") or []
            if row["effect"] not in probed and row["effect"] in table and table[row["effect"]].top_step is not None
            and (row.get("p_holm") if row.get("p_holm") is not None else 1.0) < ALPHA
            and (row.get("gamma") or 0.0) > 0 and (row.get("explained") or 0.0) < MIN_EXPLAINED]


def strength_reading(row: dict[str, Any], diagnosis: dict[str, Any]) -> str | float | None:
    """What a table should print for a ranking ``row``'s strength, the same on the page, the CLI and the
    HTML report: the estimate (in its unit, or a switch-type effect's fraction of the switch), else why there
    is none. Why: the estimate is the misfit's projection on the signature, divided by the signature's
    length; for a candidate these measurements cannot see (``calibration.unseen``) that length is noise and
    the quotient meaningless (a cohesion of -24,200 J/m2 was printed), and a negative estimate says the
    misfit points the other way from what the effect does. Returns "unseen", "opposite sign", the fraction
    (a float tagged by the caller through ``row["strength"] is None``), the strength, or None (none
    computed)."""
    if any(u.get("effect") == row.get("effect") for u in diagnosis.get("unseen") or []) and not row.get("significant"):
        return "unseen"
    value = row.get("strength")
    if value is None:
        value = row.get("fraction_of_switch")
    if value is None:
        return None
    return "opposite sign" if value < 0 else float(value)
