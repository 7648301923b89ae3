"""One verdict per iteration, from the checks in the order they matter.

Why one function: a report that says "targets out of reach" and one line below "confirmed" sends
users in two directions. The confirmation run checks the *response surfaces* (does the battery at
the optimum land where the fitted models said?); it never confirms the *model against the
measurements*. So the verdict is about the measurements, and the surface check is reported
apart, worded as what it is.
"""
from __future__ import annotations

from .vocabulary import Verdict

VERDICTS = {
    Verdict.OUT_OF_REACH: "no parameter set in the box reproduces these targets (reachability > 3): "
                            "the model lacks physics, or a measurement is wrong; see the diagnosis",
    Verdict.MISSES: "the weighted misfit exceeds what measurement and simulator noise explain "
                                     "(lack-of-fit test); see where it fails and the diagnosis",
    Verdict.SURROGATE_INADEQUATE: "the battery at the optimum lies outside the fitted models' prediction intervals: "
                            "the response surfaces need a narrower box or axial points before the physics "
                            "can be judged",
    Verdict.CALIBRATED: "the model reproduces the measurements within their noise at the optimum",
}


def verdict(*, unreachable: list, lack_of_fit_fails: bool | None, surrogate_ok: bool | None) -> dict:
    """``unreachable``: targets no parameter set reaches; ``lack_of_fit_fails``: model vs measurement;
    ``surrogate_ok``: the confirmation inside the prediction intervals (None: not testable)."""
    if unreachable:
        name = Verdict.OUT_OF_REACH
    elif lack_of_fit_fails:
        name = Verdict.MISSES
    elif surrogate_ok is False:
        name = Verdict.SURROGATE_INADEQUATE
    else:
        name = Verdict.CALIBRATED
    return {"verdict": name.value, "meaning": VERDICTS[name]}
