"""The loop's vocabulary: phases, run kinds, verdicts and stop reasons, each spelt once.

Why enums of ``str``: the values are stored in the database's JSON and string columns and read by
the page, so they must stay the plain words they were; an enum member compares equal to its word
and serialises as it. What a word means lives beside it, so the API and the page can show it.
"""
from __future__ import annotations

from enum import Enum


class Word(str, Enum):
    """A ``(str, Enum)`` whose text is its value on every Python from 3.10: ``str()`` and f-strings give
    "done", not "Phase.DONE" (3.11 made the latter the default for mixed-in enums), so a member goes
    into a message, a log line or a stored string as it is."""

    def __str__(self) -> str:
        return self.value

    __format__ = str.__format__

    @classmethod
    def values(cls) -> tuple[str, ...]:
        return tuple(member.value for member in cls)


class Probe(Word):
    """Where a diagnosis battery set a candidate's strength (calibration.attribute): at its secant step, or at
    the top of its plausible range (a second probe for a candidate the step's saw but could not name)."""

    STEP = "step"
    TOP = "top"


class Phase(Word):
    """Where an iteration is. Phases that wait for batteries: BATTERIES (the design's),
    CONFIRMATION, POLISH (one round at a time) and DIAGNOSIS; the others are computations."""

    DESIGN = "design"
    BATTERIES = "batteries"
    ANALYSIS = "analysis"
    CONFIRMATION = "confirmation"
    POLISH = "polish"
    REPORT = "report"
    DIAGNOSIS = "diagnosis"
    DIAGNOSED = "diagnosed"
    DONE = "done"


class PolishJacobian(Word):
    """Where the polishing's first Jacobian comes from (``calibration.polish``)."""

    SURFACES = "surfaces"
    BATTERIES = "batteries"


class RunKind(Word):
    """Why a battery was run: a design point, a confirmation at the optimum, a polishing step on the
    batteries themselves, or a diagnosis battery (a baseline or a candidate effect switched on)."""

    DESIGN = "design"
    CONFIRMATION = "confirmation"
    POLISH = "polish"
    DIAGNOSIS = "diagnosis"


class Verdict(Word):
    """One verdict per iteration (``calibration.verdict`` decides it, in the order the checks matter).
    "calibrated" only when every check holds; "partly calibrated" when the model as a whole passes
    but a test fails its own check (the report's ``checks`` say which hold and which do not)."""

    SUSPECT_MEASUREMENT = "suspect measurement"
    OUT_OF_REACH = "targets out of reach"
    MISSES = "model misses the measurements"
    SURROGATE_INADEQUATE = "surrogate inadequate"
    PARTLY_CALIBRATED = "partly calibrated"
    CALIBRATED = "calibrated"


# verdicts that find a misfit to diagnose
MISFIT_VERDICTS = frozenset({Verdict.SUSPECT_MEASUREMENT, Verdict.OUT_OF_REACH, Verdict.MISSES,
                             Verdict.PARTLY_CALIBRATED})


class DiagnosisVerdict(Word):
    """The diagnosis's verdict (``calibration.attribute``). Under NO_MATCH and SUSPECT_MEASUREMENT no
    effect is offered for adding (``AGAINST_ADDING``): the page shows only an override marked as
    against the diagnosis, the API asks for ``override: true``, and the automatic mode stops."""

    INDICATED = "effect indicated"
    INCONCLUSIVE = "inconclusive"
    NO_MATCH = "no physical match"
    SUSPECT_MEASUREMENT = "suspect measurement"
    NO_MISFIT = "no misfit"


AGAINST_ADDING = frozenset({DiagnosisVerdict.NO_MATCH, DiagnosisVerdict.SUSPECT_MEASUREMENT})


class Explains(Word):
    """What an added effect did to the misfit (``calibration.decisions.explanation``): it explains it
    only when the iteration with it is "calibrated"; an effect that lowers the misfit without bringing
    it into the noise is reported with the misfit it leaves, never as the answer."""

    EXPLAINS = "explains"
    PARTLY = "partly explains"
    DOES_NOT = "does not explain"


class StopReason(Word):
    """Why the automatic mode stopped. Three are fixed words; the others carry the diagnosis's
    verdict or the reason the next iteration cannot run, after these prefixes."""

    PASSES = "lack of fit passes"
    UNTESTABLE = "lack of fit not testable"  # as many free parameters as measured values: nothing left to test
    SUSPECT_MEASUREMENT = "suspect measurement: "  # + the measurement and its likely unit slip
    MAX_ITERATIONS = "maximum number of iterations reached"
    NOTHING_IMPROVES = "nothing improves"
    DIAGNOSIS = "diagnosis: "            # + the diagnosis's verdict
    CANNOT_RUN = "the next iteration with "  # + effect + " cannot run: " + why


class PolishStage(Word):
    """Where a polishing round is: the Jacobian's points, a Gauss-Newton step's trial lengths, the held-out
    confirmation at the point the steps chose (``calibration.polish.hold_out``), or done."""

    JACOBIAN = "jacobian"
    STEP = "step"
    HOLDOUT = "holdout"
    DONE = "done"


class PolishRule(Word):
    """When an iteration polishes its optimum on the batteries (``LoopSettings.polish_when``)."""

    ALWAYS = "always"
    SURROGATE_MISSES = "surrogate_misses"
