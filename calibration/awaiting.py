"""Which runs an iteration's phase waits for: the machine's rule, in a module of its own so that a
client showing progress (``demcal campaign status``) can apply it without importing the loop's
statistics (numpy, statsmodels: seconds of start-up per command)."""
from __future__ import annotations

from calibration.vocabulary import Phase, PolishStage, RunKind

ROUND = 1000  # std_order of a polish run = round x ROUND + index + 1


def runs_of(it, kind: RunKind) -> list:
    return [r for r in it.runs if r.kind == kind]


def round_runs(it, state: dict) -> list:
    """The runs of the polishing state's current round, in std_order (each point's runs at every seed in turn)."""
    return sorted((r for r in it.runs if r.kind == RunKind.POLISH and r.std_order // ROUND == state["round"]),
                  key=lambda r: r.std_order)


def awaited(it) -> list:
    """The runs the iteration's phase waits for (all must have succeeded before ``machine.step``); their
    number is known when the phase starts. ``it``: anything with ``phase``, ``runs`` (``kind``,
    ``std_order``) and ``optimum`` (whose ``polish`` is the polishing's state)."""
    phase = Phase(it.phase)
    if phase == Phase.BATTERIES:
        return runs_of(it, RunKind.DESIGN)
    if phase == Phase.CONFIRMATION:
        return runs_of(it, RunKind.CONFIRMATION)
    if phase == Phase.DIAGNOSIS:
        return runs_of(it, RunKind.DIAGNOSIS)
    if phase == Phase.POLISH:
        state = (it.optimum or {}).get("polish")
        if state and state["stage"] != PolishStage.DONE:
            return round_runs(it, state)
    return []
