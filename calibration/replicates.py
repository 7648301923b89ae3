"""How many seeds the diagnosis runs: replicates where they buy power, and only there (issue 34, item 2).

Why: the diagnosis ran a baseline and every candidate at each confirmation seed, 2 x (1 + 4) = 10
batteries, whatever the first seed had already shown. A seed buys power only when the simulator's
scatter is a large part of what a signature is compared against, and only when the decision could still
go the other way. So the diagnosis runs in two stages:

1. **One seed** (a baseline and each candidate at the first of the diagnosis's own seeds): the ranking,
   the directed test and the verdict as always.
2. **The other seeds** only when both hold:
   * **the decision is close**: no effect is claimed with Holm p below ``ALPHA_FIRST`` = alpha / 20 apart
     from rivals the evidence cannot yet separate from it (an alias group made by ``separation_z``;
     one made by collinear signatures is physics that more seeds cannot separate), and not every
     candidate is futile (Holm p above ``FUTILE_P``); a "no misfit" verdict is never close (more seeds
     cannot make a fitting model miss);
   * or **the ranking is close**: the leader is claimed decisively but a rival also explains the misfit
     (Holm p below alpha, in the direction the effect acts) and would reach the leader's score once the
     attenuation its signature's noise causes is undone (``rivals``), while the simulator's scatter
     matters (below). Noise in a signature shrinks its score as a regressor measured with error explains
     less than the true one would, so a rival whose probe landed on an unlucky packing ranks below an
     effect it would beat: which of two real contenders is named first is decided on every seed
     (tier B shape_strong, docs/diagnosis.md);
   * or **the leader's own probe is mostly noise**: its signature's expected noise is at least its
     projected length (``attribute.noise_share`` >= 1), so its direction is mostly the packing's scatter
     and its score says how well a random direction happens to meet the misfit, which the directed
     test's p-value (made for a known signature) does not price; every seed's average decides. Tier B's
     weak Hertz world (session 35) named cohesion at one seed with Holm p 0.00044 from a probe whose
     noise was 1.42 of its length, tried it, and turned it off: Hertz, hidden, ranked third;
   * **the simulator's scatter matters**: a signature is a difference of two battery means, variance
     2 s_sim^2 / m, and it is read against residuals of variance v (measurement, discrepancy and the
     confirmation's share of s_sim^2); where the median over targets of 2 s_sim^2 / v is below
     ``SIMULATOR_SHARE_MIN`` = 1/4, the measurement's scatter dominates and one seed's signature is as
     good as the mean of several (its noise inflates the residual noise it is compared with by at most
     12 % in standard deviation).

Size: an effect is claimed at stage 1 only with Holm p < alpha / 20, and at stage 2 at alpha on all the
seeds, so the chance of a false claim is at most alpha / 20 + alpha = 0.0525 at alpha 0.05 (a union
bound; stopping for futility adds nothing).
"""
from __future__ import annotations

import statistics
from typing import Any

from .localise import ALPHA
from .vocabulary import DiagnosisVerdict

ALPHA_FIRST = ALPHA / 20
FUTILE_P = 0.5
SIMULATOR_SHARE_MIN = 0.25


def first_stage(seeds: list[int], adaptive: bool) -> list[int]:
    """The seeds the diagnosis starts with: the first only, when the number of seeds is decided from it."""
    return list(seeds[:1]) if adaptive and len(seeds) > 1 else list(seeds)


def simulator_share(simulator_sd: dict, residual_sd: dict) -> float | None:
    """Median over targets of 2 s_sim^2 / v (signature noise of one seed over the residual's variance);
    None when no target has both."""
    ratios = [2.0 * simulator_sd[k] ** 2 / residual_sd[k] ** 2 for k in simulator_sd
              if k in residual_sd and simulator_sd[k] is not None and residual_sd[k]]
    return statistics.median(ratios) if ratios else None


def decided(diagnosis: dict[str, Any], share: float | None = None) -> str | None:
    """Why one seed's diagnosis is final, or None when the decision is close (module docstring).
    ``share``: the simulator's share of the residuals' variance (``simulator_share``; None: unknown, so
    it may matter), which decides whether a significant rival keeps the ranking open."""
    verdict = diagnosis.get("verdict")
    if verdict == DiagnosisVerdict.NO_MISFIT:
        return "no misfit to explain"
    ranking = diagnosis.get("ranking") or []
    if not ranking:
        return "no candidate to rank"
    leader = ranking[0]
    if leader["effect"] in (diagnosis.get("indicated") or []) and leader["p_holm"] < ALPHA_FIRST \
            and not _separable_by_seeds(diagnosis, leader["effect"]) \
            and not ((rivals(diagnosis) or noisy_leader(diagnosis)) and (share is None or share >= SIMULATOR_SHARE_MIN)):
        return f"{leader['effect']} indicated with Holm p {leader['p_holm']:.2g} < {ALPHA_FIRST:g}"
    if all(r["p_holm"] > FUTILE_P for r in ranking):
        return f"every candidate's Holm p above {FUTILE_P:g}"
    return None


def rivals(diagnosis: dict[str, Any]) -> list[str]:
    """The candidates after the leader that could outrank it once their signatures' noise is averaged away.

    A rival explains the misfit too (Holm p below alpha, with a positive strength: a negative one would
    undo the misfit's direction, which no effect that is off can do), and its score corrected for the
    attenuation its signature's noise causes, LM / (1 - signature_noise) (``attribute.noise_share``),
    reaches the leader's score as observed. A signature that is mostly noise (share >= 1) could be anything.
    """
    ranking = diagnosis.get("ranking") or []
    if not ranking:
        return []
    lead = float(ranking[0].get("lm") or 0.0)
    out = []
    for r in ranking[1:]:
        if not (r.get("p_holm", 1.0) < ALPHA and (r.get("gamma") is None or r["gamma"] > 0)):
            continue
        share = float(r.get("signature_noise") or 0.0)
        if share >= 1.0 or float(r.get("lm") or 0.0) / (1.0 - share) >= lead:
            out.append(r["effect"])
    return out


def noisy_leader(diagnosis: dict[str, Any]) -> float | None:
    """The leader's probe noise share when it is mostly noise (``attribute.noise_share`` >= 1), else None."""
    ranking = diagnosis.get("ranking") or []
    share = float(ranking[0].get("signature_noise") or 0.0) if ranking else 0.0
    return share if share >= 1.0 else None


def _separable_by_seeds(diagnosis: dict[str, Any], effect: str) -> bool:
    """Is ``effect`` grouped with a rival only by the evidence (``separation_z`` below its bound), which
    more seeds can sharpen? A group made by collinear signatures (|cos| > 0.9, no separation_z) is the
    effects' physics: more batteries at the optimum cannot tell them apart, refitting each can."""
    for group in diagnosis.get("alias_groups") or []:
        if effect in group["effects"] and any(
                effect in sep["effects"] and sep.get("separation_z") is not None for sep in group.get("separators", [])):
            return True
    return False


def more_seeds(diagnosis: dict[str, Any], share: float | None) -> tuple[bool, str]:
    """(run the other seeds?, why), from one seed's diagnosis and the simulator's share of the noise."""
    reason = decided(diagnosis, share)
    if reason is not None:
        return False, f"one seed decides: {reason}"
    if share is not None and share < SIMULATOR_SHARE_MIN:
        return False, (f"one seed suffices: the measurements' scatter dominates (a signature's simulator noise "
                       f"{share:.2f} of the residuals' variance, below {SIMULATOR_SHARE_MIN:g})")
    where = "unknown" if share is None else f"{share:.2f} of the residuals' variance"
    if decided(diagnosis, 0.0) is not None:  # decided but for a rival the first seed's noise may have sunk
        close = []
        if rivals(diagnosis):
            close.append(f"{', '.join(rivals(diagnosis))} also explain(s) the misfit")
        if (noise := noisy_leader(diagnosis)) is not None:
            close.append(f"the leader's probe is mostly the simulator's scatter ({noise:.2g} of its signature)")
        return True, (f"the ranking is close ({'; '.join(close)}) and the simulator's scatter matters ({where}): "
                      "the other seeds run")
    return True, f"the decision is close and the simulator's scatter matters ({where}): the other seeds run"
