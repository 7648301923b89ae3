"""The loop's two judgements, shared by the library loop and the service's automatic mode.

* ``effect_range``: the range an added effect's strength gets as a design factor.
* ``judge``: whether an iteration with an added effect earned its place over the one before
  (design note step 6): the weighted error must fall without a passing lack of fit turned into a
  failing one, and the fall must be significant, by the boundary-corrected likelihood-ratio test for
  an effect that vanishes at its "off" strength (Self & Liang 1987: 1/2 chi2_0 + 1/2 chi2_1) or, for
  a switch-type effect (not nested), by BIC.

Both work on plain numbers, so the service can call them on what it stored in the database.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from engine.effects.base import Candidate

from . import parameters as params_mod
from . import stats
from .attribute import PLAUSIBLE_SLACK
from .localise import ALPHA
from .verdict import failing_tests
from .vocabulary import Explains, Verdict


def effect_range(candidate: Candidate, strength: float | None = None,
                 reference: float | None = None) -> tuple[float, float, bool]:
    """(low, high, log) of the added effect's strength factor.

    A switch-type effect (no "off" strength) spans a factor of 4 either way about its matched
    strength (``reference``, or the diagnosis's estimate ``strength``), on a log scale. Any other
    spans from "off" over the whole plausible range, or to twice the diagnosis's estimate if that is
    larger (a linear signature underestimates a saturating effect), at most PLAUSIBLE_SLACK x the
    plausible span and never past the engine's limit; a strength pinned at the top gets a wider
    range (``widened_top``). A narrower box about the estimate (0 to 2x) was tried in session 14
    and dropped: on the DEM engine the rolling strength was pinned at its top in both fidelities
    (mu_r 0.247 at 20 mm, 0.306 at 35 mm, for a true 0.15), so it only cost an iteration.
    """
    if candidate.is_switch:
        centre = strength if strength else reference
        if centre is None or not centre > 0:
            raise ValueError(f"{candidate.name}: a switch-type effect needs its matched strength")
        return centre / 4.0, centre * 4.0, True
    off = candidate.off_value or 0.0
    span = candidate.plausible_range[1] - off
    gamma = strength - off if strength is not None else candidate.step
    return off, min(off + min(max(2.0 * gamma, span), PLAUSIBLE_SLACK * span), _cap(candidate)), False


def _cap(candidate: Candidate) -> float:
    off = candidate.off_value or 0.0
    return min(off + PLAUSIBLE_SLACK * (candidate.plausible_range[1] - off), params_mod.upper_limit(candidate.factor))


def widened_top(candidate: Candidate, high: float) -> float | None:
    """The top of a range twice as wide from "off" for an added strength pinned at its ``high``
    bound, up to PLAUSIBLE_SLACK x the plausible span and the engine's limit; None when the range
    already reaches that cap or the effect is a switch (its log range is about a matched value)."""
    if candidate.is_switch:
        return None
    off = candidate.off_value or 0.0
    cap = _cap(candidate)
    if not high < cap * (1.0 - 1e-9):
        return None
    return min(cap, off + 2.0 * (high - off))


def widened_box(factor: dict, side: str, first: dict | None = None, prior=None) -> dict | None:
    """The base factor ``factor`` ({"name", "low", "high", "log"?}) with its ``side`` ("low" or "high")
    moved out by the box's width (on a log factor, by its ratio), but not past where the parameter's
    values usually lie (``parameters.typical_range``); None when that side already reaches it, the
    factor is an effect's strength (``widened_top`` widens those), or the side was widened before:
    ``first`` is the factor as the campaign's first iteration had it, and a side already beyond it is
    left alone (once, as an effect's range). ``prior`` (a ``settings.PriorIn``: the parameter measured
    directly) keeps the box where the edge lies more than 2 of its sd from the measured value: the data
    pushing a measured parameter away from its measurement is a conflict to report, not room to give.

    Why: an optimum pinned at a box edge with the misfit pushing outward is either a box drawn too
    narrow or a parameter compensating for missing physics (``localise.conflicts``). Where the edge
    is the parameter's plausible limit (a friction coefficient at 1.0) it is the second, and the
    diagnosis's job; where it is not (a contact stiffness at 3 MN/m, whose typical range runs to
    1e10 N/m) a wider box is the cheaper explanation, and an effect added on top of it would be asked
    to make up for the box. The founding case's spheres with rolling resistance pinned the stiffness at
    the README box's 3 MN/m with E' still 3.4 sd low."""
    typical = params_mod.typical_range(factor["name"])
    if typical is None:
        return None
    low, high = float(factor["low"]), float(factor["high"])
    if prior is not None and abs((high if side == "high" else low) - prior.value) > 2.0 * prior.uncertainty:
        return None
    if first is not None and ((side == "high" and high > float(first["high"]) * (1 + 1e-9))
                              or (side == "low" and low < float(first["low"]) * (1 - 1e-9))):
        return None
    log = bool(factor.get("log"))
    if side == "high":
        edge = min(high * (high / low) if log else high + (high - low), typical[1])
        return {**factor, "high": edge} if edge > high * (1 + 1e-9) else None
    edge = max(low * (low / high) if log else low - (high - low), typical[0])
    return {**factor, "low": edge} if edge < low * (1 - 1e-9) else None


@dataclass
class Decision:
    """Whether an added effect earned its place."""

    effect: str
    accepted: bool
    chi2_before: float
    chi2_after: float
    lr: float
    p_value: float | None            # boundary-corrected LR test; None for a switch (not nested)
    delta_bic: float
    lof_p_before: float
    lof_p_after: float
    strength: float | None
    turned_off: bool = False          # the optimum put the effect at its "off" strength (never accepted)

    def to_dict(self) -> dict[str, Any]:
        return dict(self.__dict__)


def judge(candidate: Candidate, *, chi2_before: float, chi2_after: float, n_residuals: int,
          free_before: int, free_after: int, lof_p_before: float, lof_p_after: float,
          strength: float | None = None, turned_off: bool = False) -> Decision:
    """The added effect is accepted when the weighted error falls, a lack of fit that passed still
    passes, and the fall is significant (LR p < ALPHA, or BIC falls by more than 2), and never when
    the optimum puts it at its "off" strength (``turned_off``).

    Why ``turned_off``: the likelihood-ratio test reads the fall in chi2 as the effect's, which holds only
    when the base's chi2 is at the base model's own best fit. It is not always: an iteration that polishes
    on the batteries (or confirms at other seeds) can find a better base fit than the iteration it is
    judged against. Tier B's weak Hertz world (session 35) showed it: cohesion added, the polish drove the
    surface energy to 3e-12 J/m2 and friction from 0.73 to 0.58, chi2 fell from 29.8 to 16.2 (LR p 1e-4),
    and the effect that was "accepted" was not in the model at all.

    Why the lack of fit is compared by its outcome and not by its p-value: each iteration's p-value
    is read against that iteration's own null (the simulator's scatter at its own confirmation
    points, drawn by Monte Carlo), so two p-values below ALPHA are two statements "far outside the
    noise", both at the resolution of the draws, and their order says nothing about which fit is
    better. The founding case showed it: rolling resistance took chi2 from 68.7 to 18.6 on the same
    four residuals (LR p 7e-13), and was rejected because the second p-value (5 draws in 20,001
    beyond it) was below the first (12 in 20,001). Between two failing fits the likelihood-ratio
    test on the same residuals decides; the effect is then kept as "partly explains"
    (``explanation``) and the misfit it leaves goes to the next diagnosis."""
    lr = chi2_before - chi2_after
    p = None if candidate.is_switch else stats.boundary_lr_pvalue(lr)
    delta_bic = stats.bic(chi2_after, free_after, n_residuals) - stats.bic(chi2_before, free_before, n_residuals)
    turned_failing = lof_p_before >= ALPHA and lof_p_after < ALPHA
    improves = chi2_after < chi2_before and not turned_failing
    significant = (p is not None and p < ALPHA) or delta_bic < -2.0
    return Decision(candidate.name, bool(improves and significant and not turned_off), float(chi2_before),
                    float(chi2_after), float(lr), p, float(delta_bic), float(lof_p_before), float(lof_p_after),
                    strength, bool(turned_off))


def explanation(effects: list[str], kept: bool, before: dict, after: dict, turned_off: bool = False) -> dict[str, Any]:
    """How much of the misfit the added ``effects`` explain, judged on the report of the iteration with
    them (``after``) against the one it was built on (``before``): "explains" only when its verdict is
    "calibrated" (every check holds); "partly explains" when the effect was kept but the fit is still
    outside the noise or a test still fails, with the misfit that remains; else "does not explain".
    ``kept``: the automatic mode's decision; added by hand, whether chi2 fell."""
    lof_before, lof = before.get("lack_of_fit") or {}, after.get("lack_of_fit") or {}
    verdict = after.get("verdict")
    if kept and verdict == Verdict.CALIBRATED:
        word = Explains.EXPLAINS
    elif kept:
        word = Explains.PARTLY
    else:
        word = Explains.DOES_NOT
    failing = failing_tests(after.get("tests"))
    band = lof.get("noise_band") or [None, None]
    remaining = {"verdict": verdict, "chi2_per_dof": lof.get("chi2_per_dof"), "noise_band": lof.get("noise_band"),
                 "p_value": (after.get("adequacy") or {}).get("p_value", lof.get("p_value")),
                 "failing_tests": failing}
    text = f"{' + '.join(effects)} {word.value} the misfit: chi2/dof {_g(lof_before.get('chi2_per_dof'))} -> " \
           f"{_g(lof.get('chi2_per_dof'))} (noise band {_g(band[0])}-{_g(band[1])}), verdict {verdict}"
    if failing:
        text += f", failing tests: {', '.join(failing)}"
    if word == Explains.PARTLY:
        text += "; the misfit left is not explained by it"
    if turned_off:
        text += "; the fit sets it to its off strength, so what changed is the base parameters' fit"
    return {"explains": word.value, "remaining": remaining, "explains_message": text}


def _g(value) -> str:
    return "-" if value is None else f"{value:.3g}"
