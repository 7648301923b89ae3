"""One verdict per iteration, from the checks in the order they matter, and the checks themselves.

Why one function: a report that says "targets out of reach" and one line below "confirmed" sends
users in two directions. The confirmation run checks the *response surfaces* (does the battery at
the optimum land where the fitted models said?); it never confirms the *model against the
measurements*. So the verdict is about the measurements, and the surface check is reported
apart, worded as what it is.

Why "calibrated" needs every check: a page that prints "calibrated" beside "failing tests: dst" in
red contradicts itself. The adequacy test judges the misfit as a whole; each lab test's own check
(its share of the misfit against the same null, Holm over the tests) can fail while the whole
passes, when one test carries the misfit. Then the verdict is "partly calibrated" and the report's
``checks`` say what holds and what does not, one line each.
"""
from __future__ import annotations

from typing import Any

from .vocabulary import Verdict

VERDICTS = {
    Verdict.SUSPECT_MEASUREMENT: "a measurement lies far outside anything the model reaches and no candidate "
                                 "effect moves it there: check its value and unit before adding physics",
    Verdict.OUT_OF_REACH: "no parameter set in the box reproduces these targets (reachability > 3): "
                            "the model lacks physics, or a measurement is wrong; see the diagnosis",
    Verdict.MISSES: "the weighted misfit exceeds what measurement and simulator noise explain "
                                     "(lack-of-fit test); see where it fails and the diagnosis",
    Verdict.SURROGATE_INADEQUATE: "the battery at the optimum lies outside the fitted models' prediction intervals: "
                            "the response surfaces need a narrower box or axial points before the physics "
                            "can be judged",
    Verdict.PARTLY_CALIBRATED: "the misfit as a whole lies within the noise, but {tests} fail{s} {their} own "
                               "check: the model reproduces the other tests, not {these}; see the diagnosis",
    Verdict.CALIBRATED: "the model reproduces the measurements within their noise at the optimum",
}
# "partly calibrated" without a failing test: the fit could not be tested at all
UNTESTED = ("the targets are matched, but with as many free parameters as measured values no misfit is left to test "
            "the model against their noise: measure more (each shear load, E' at several stresses) or fix "
            "parameters measured directly")

UNCONFIRMED = ("no simulated response was confirmed by batteries at the optimum, so the fit has not been compared with "
               "the measurements at all: see the surrogate check and the targets the virtual lab does not simulate")

TEST_NAMES = {"prior": "the directly measured parameters (priors)"}


def _test_name(test: str) -> str:
    return TEST_NAMES.get(test, test)


def verdict(*, unreachable: list, lack_of_fit_fails: bool | None, surrogate_ok: bool | None,
            failing_tests: list[str] = (), suspects: list[dict] = (), lack_of_fit: dict | None = None,
            adequacy_p: float | None = None) -> dict[str, Any]:
    """``unreachable``: targets no parameter set reaches; ``lack_of_fit_fails``: model vs measurement
    (the omnibus test, or once diagnosed the adequacy test); ``surrogate_ok``: the confirmation inside
    the prediction intervals (None: not testable); ``failing_tests``: lab tests whose own check fails
    (the localisation's ``tests[].fails``); ``suspects``: suspect measurements
    (``calibration.suspect``); ``lack_of_fit``/``adequacy_p``: the numbers the checks quote."""
    failing = list(dict.fromkeys(failing_tests))
    if suspects:
        name = Verdict.SUSPECT_MEASUREMENT
    elif unreachable:
        name = Verdict.OUT_OF_REACH
    elif lack_of_fit_fails:
        name = Verdict.MISSES
    elif surrogate_ok is False:
        name = Verdict.SURROGATE_INADEQUATE
    elif failing or lack_of_fit_fails is None:
        # a failing test, or no test at all: "calibrated" needs the adequacy test made and passed
        name = Verdict.PARTLY_CALIBRATED
    else:
        name = Verdict.CALIBRATED
    meaning = VERDICTS[name]
    if name == Verdict.PARTLY_CALIBRATED and not failing:
        meaning = UNTESTED if lack_of_fit is not None else UNCONFIRMED
    elif name == Verdict.PARTLY_CALIBRATED:
        names = ", ".join(_test_name(t) for t in failing)
        one = len(failing) == 1
        meaning = meaning.format(tests=names, s="s" if one else "", their="its" if one else "their",
                                 these="that test" if one else "those tests")
    elif name == Verdict.SUSPECT_MEASUREMENT:
        meaning = f"{meaning}: " + "; ".join(s["message"] for s in suspects)
    return {"verdict": name.value, "meaning": meaning,
            "checks": checks(unreachable=unreachable, lack_of_fit_fails=lack_of_fit_fails, surrogate_ok=surrogate_ok,
                             failing_tests=failing, suspects=list(suspects), lack_of_fit=lack_of_fit,
                             adequacy_p=adequacy_p)}


def checks(*, unreachable, lack_of_fit_fails, surrogate_ok, failing_tests, suspects, lack_of_fit, adequacy_p) -> list[dict]:
    """What holds and what does not, one row per check: ``{"check", "holds" (True, False or None: not
    made), "detail"}``; the verdict is the first failing row's, in this order."""
    rows = [{"check": "measurements plausible against the model's reach", "holds": not suspects,
             "detail": "; ".join(s["message"] for s in suspects) or "no measured quantity lies an order of magnitude "
                                                                   "beyond what the model reaches"},
            {"check": "targets within reach", "holds": not unreachable,
             "detail": ("out of reach: " + ", ".join(unreachable)) if unreachable else
             "every target is reachable by some parameter set in the box"}]
    lof = lack_of_fit or {}
    detail = ("not testable (no degrees of freedom left)" if lack_of_fit is not None else
              "not made (nothing confirmed at the optimum)") if lack_of_fit_fails is None else (
        "the misfit exceeds the noise" if lack_of_fit_fails else "the misfit lies within the noise")
    per_dof, band, p = lof.get("chi2_per_dof"), lof.get("noise_band") or [None, None], lof.get("p_value")
    if lack_of_fit_fails is not None and per_dof is not None and band[1] is not None:
        detail += f": chi2/dof {per_dof:.3g} on {lof.get('dof')} dof, p {p:.3g}"
        if adequacy_p is not None:
            detail += f"; with the candidates' directed test (Holm) p {adequacy_p:.3g}"
        if lack_of_fit_fails is False and per_dof > band[1]:
            # the band is chi-square's (known variances); the p-value refers the sum to its own null, whose
            # tail is heavier with variances from few replicates: say so rather than leave the two apart
            detail += (f"; chi2/dof lies above the chi-square band {band[0]:.3g}-{band[1]:.3g}, which assumes "
                       "known variances: with variances from few replicates chance reaches it (the p-value)")
    rows.append({"check": "model against the measurements (adequacy)", "holds": None if lack_of_fit_fails is None
                 else not lack_of_fit_fails, "detail": detail})
    rows.append({"check": "each test on its own", "holds": not failing_tests,
                 "detail": ("failing: " + ", ".join(_test_name(t) for t in failing_tests)) if failing_tests else
                 "no test carries more misfit than its noise explains (Holm over the tests)"})
    rows.append({"check": "response surfaces at the optimum", "holds": surrogate_ok,
                 "detail": {True: "the batteries at the optimum lie inside the surfaces' prediction intervals",
                            False: "the batteries at the optimum lie outside the surfaces' prediction intervals",
                            None: "not judged (not testable, or the optimum was polished on the batteries)"}[surrogate_ok]})
    return rows


def failing_tests(tests: list[dict] | None) -> list[str]:
    """The lab tests (and the priors' group) whose own check fails, in the report's order."""
    return [t["test"] for t in tests or [] if t.get("fails")]
