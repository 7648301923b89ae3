"""Which candidate effects the measurements could not see: a power statement for "no misfit".

"The model agrees with the measurements" says nothing of an effect the measured quantities do not respond
to. A candidate's projected signature |M s| (what the baseline parameters cannot absorb, per unit
strength) gives the noncentrality its score test would have if the effect were present at strength g:
lambda = g^2 |M s|^2. The one-sided score test's root sqrt(LM) is then N(sqrt(lambda), 1), so it clears
Holm's first step (critical LM c among k candidates) with probability Phi(sqrt(lambda) - sqrt(c)):
``DETECTION_POWER`` needs lambda >= (sqrt(c) + z_power)^2. A candidate whose lambda stays below that even
at the top of its plausible range (the full switch for a law that replaces the baseline's) is unseen: a
"no misfit" does not speak for or against it, and the report names the measurement that would.

The probe measures s with the simulator's scatter e (``attribute.signature_noise_var``), and a short
projected signature is also what a noisy probe of a long one can give. "Unseen" is a claim about the true
signature, so it is judged on an upper bound of its length: |M s_true| <= |M s| + |M e|, with |M e| at most
1.96 sqrt(E|M e|^2) (95 %, the noise taken as if all in one direction, the conservative case). A probe
whose noise could hide a visible signature names nothing: on tier B's weak Hertz scenario one seed's
cohesion probe was 2.2 times its own length in noise, and cohesion at 80 J/m2 had been seen there.

Between the two lies a candidate whose probe is too noisy to say either way: the upper bound of its length
would be seen, the lower bound (|M s| - 1.96 sqrt(E|M e|^2), at least 0) would not. "No misfit" does not
rule it out either; ``undetermined`` names such candidates with what would decide (tier B's weak Hertz
world, session 35: the Hertz probe's scatter 1.17 times its projected signature, LM 0.77, and Hertz hidden).

Why it matters: on tier B's packings the loading E' grows with the contact network under either contact
law, so E' windows left a Hertzian world inside the linear model's noise, while the unload-reload modulus
saw it (docs/diagnosis.md, hertz_strong; ``Candidate.revealed_by`` names it). The signature is a linear
probe: for a saturating effect the strength is a first-order figure, as the diagnosis's own estimates are.
"""
from __future__ import annotations

import math
from typing import Any

import numpy as np
from scipy import stats as sps

# an effect counts as visible when the score test would flag it at least this often
DETECTION_POWER = 0.8
# the probe's noise bound on a projected signature's length: 1.96 of its root-mean-square (95 %)
NOISE_Z = 1.96


def critical_lm(alpha: float, k: int) -> float:
    """LM one effect needs to clear Holm's first (strictest) step among k one-sided score tests."""
    return float(sps.chi2.isf(2.0 * alpha / k, 1)) if k > 0 else math.nan


def detectable_lm(alpha: float, k: int, power: float = DETECTION_POWER) -> float:
    """The noncentrality at which the one-sided score test clears ``critical_lm`` with probability ``power``:
    (sqrt(c) + z_power)^2 (for k = 1, alpha 0.05, power 0.8: (1.645 + 0.842)^2 = 6.18)."""
    return (math.sqrt(critical_lm(alpha, k)) + float(sps.norm.ppf(power))) ** 2


def _top_strength(candidate) -> float:
    """The strength change from "off" to the top of the plausible range; 1 for a switch (the full switch)."""
    if candidate.is_switch:
        return 1.0
    return float(candidate.plausible_range[1]) - float(candidate.off_value or 0.0)


def unseen(signatures, M: np.ndarray, alpha: float, measured_labels: set[str] | None = None) -> list[dict[str, Any]]:
    """The candidates these measurements could not see at any plausible strength, each with the noncentrality
    at the range's top (on the upper bound of its signature's length), the one needed, the smallest strength that would be seen (None: none would) and what
    to measure: its ``revealed_by`` measurements, "more replicates of" those already measured."""
    need = detectable_lm(alpha, len(signatures))
    out = []
    for sig in signatures:
        c = sig.candidate
        _, upper2, share = _length_bounds(sig, M)
        lm_top = upper2 * _top_strength(c) ** 2
        if lm_top >= need:
            continue
        smallest = None
        if upper2 > 0.0:
            g = math.sqrt(need / upper2)
            smallest = g if c.is_switch else float(c.off_value or 0.0) + g
        out.append({"effect": c.name, "title": c.title, "lm_at_top": lm_top, "lm_needed": need,
                    "power": DETECTION_POWER, "smallest_seen": smallest, "signature_noise": share,
                    "measure": [_advice(test, quantity, how, measured_labels) for test, quantity, how in c.revealed_by]})
    return out


def undetermined(signatures, M: np.ndarray, alpha: float,
                 measured_labels: set[str] | None = None) -> list[dict[str, Any]]:
    """The candidates whose probes cannot say whether these measurements would see them at the top of their
    plausible range: seen on the upper bound of the signature's length, unseen on the lower. Each with its
    noncentrality at the top on both bounds, the one needed, the probe's noise share, and what would decide:
    its ``revealed_by`` measurements (or more replicates of them)."""
    need = detectable_lm(alpha, len(signatures))
    out = []
    for sig in signatures:
        c = sig.candidate
        lower2, upper2, share = _length_bounds(sig, M)
        top2 = _top_strength(c) ** 2
        if upper2 * top2 < need or lower2 * top2 >= need:
            continue  # unseen (``unseen`` names it) or seen whatever the probe's scatter
        out.append({"effect": c.name, "title": c.title, "lm_at_top_low": lower2 * top2,
                    "lm_at_top_high": upper2 * top2,
                    "lm_needed": need, "power": DETECTION_POWER, "signature_noise": share,
                    "measure": [_advice(test, quantity, how, measured_labels) for test, quantity, how in c.revealed_by]})
    return out


def undetermined_message(rows: list[dict[str, Any]]) -> str:
    """One sentence: which candidates the probes could not judge, and what would."""
    if not rows:
        return ""
    parts = []
    for row in rows:
        what = (f"{row['title']} ({row['effect']}): its probe's scatter is {row['signature_noise']:.2g} of its "
                f"signature, LM {row['lm_at_top_low']:.1f}-{row['lm_at_top_high']:.1f} at its strongest "
                "plausible strength")
        parts.append(what + (f"; measure {' or '.join(row['measure'])}" if row["measure"] else ""))
    return (f"whether these measurements would see {len(rows)} candidate effect{'s' if len(rows) > 1 else ''} "
            f"(LM {rows[0]['lm_needed']:.1f} needed) is not known, so the agreement does not rule "
            f"{'them' if len(rows) > 1 else 'it'} out: " + "; ".join(parts))


def _length_bounds(sig, M: np.ndarray) -> tuple[float, float, float | None]:
    """(lower, upper) squared bounds on the true projected signature's length, and the probe's noise share."""
    from calibration.attribute import noise_share

    projected = M @ np.asarray(sig.vector, float)
    length = math.sqrt(float(projected @ projected))
    spread = NOISE_Z * math.sqrt(_noise2(M, sig.noise_var))
    return max(length - spread, 0.0) ** 2, (length + spread) ** 2, noise_share(M, sig.vector, sig.noise_var)


def _noise2(M: np.ndarray, noise_var) -> float:
    """E|M e|^2 of a probe's noise (``attribute.noise_share``'s numerator); 0 when not known."""
    if noise_var is None:
        return 0.0
    return float(np.sum(np.asarray(noise_var, float) * np.sum(M * M, axis=0)))


def _advice(test: str, quantity: str, how: str, measured_labels: set[str] | None) -> str:
    """ "test quantity how", or "more replicates of ..." when the target list already holds that quantity."""
    text = f"{test} {quantity}" + (f" {how}" if how else "")
    measured = measured_labels is not None and any(label.split(" @ ")[0] == f"{test} {quantity}"
                                                   for label in measured_labels)
    return f"more replicates of {text}" if measured else text


def message(rows: list[dict[str, Any]]) -> str:
    """One sentence for the diagnosis's message: what was unseen and what would see it."""
    if not rows:
        return ""
    parts = []
    for row in rows:
        what = f"{row['title']} ({row['effect']}): LM {row['lm_at_top']:.1f} at its strongest plausible strength"
        parts.append(what + (f"; measure {' or '.join(row['measure'])}" if row["measure"] else ""))
    return ("these measurements could not see, with "
            f"{100 * rows[0]['power']:.0f} % power, {len(rows)} candidate effect{'s' if len(rows) > 1 else ''} "
            f"(LM {rows[0]['lm_needed']:.1f} needed): " + "; ".join(parts))
