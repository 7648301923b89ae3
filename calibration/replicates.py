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


def decided(diagnosis: dict[str, Any]) -> str | None:
    """Why one seed's diagnosis is final, or None when the decision is close (module docstring)."""
    verdict = diagnosis.get("verdict")
    if verdict == DiagnosisVerdict.NO_MISFIT:
        return "no misfit to explain"
    ranking = diagnosis.get("ranking") or []
    if not ranking:
        return "no candidate to rank"
    leader = ranking[0]
    if leader["effect"] in (diagnosis.get("indicated") or []) and leader["p_holm"] < ALPHA_FIRST \
            and not _separable_by_seeds(diagnosis, leader["effect"]):
        return f"{leader['effect']} indicated with Holm p {leader['p_holm']:.2g} < {ALPHA_FIRST:g}"
    if all(r["p_holm"] > FUTILE_P for r in ranking):
        return f"every candidate's Holm p above {FUTILE_P:g}"
    return None


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
    reason = decided(diagnosis)
    if reason is not None:
        return False, f"one seed decides: {reason}"
    if share is not None and share < SIMULATOR_SHARE_MIN:
        return False, (f"one seed suffices: the measurements' scatter dominates (a signature's simulator noise "
                       f"{share:.2f} of the residuals' variance, below {SIMULATOR_SHARE_MIN:g})")
    where = "unknown" if share is None else f"{share:.2f} of the residuals' variance"
    return True, f"the decision is close and the simulator's scatter matters ({where}): the other seeds run"
