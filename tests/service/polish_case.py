"""A polish with anchors as the loop writes it, for the page's and the CLI's tests.

The case is tests/calibration/test_polish_prior.py's (tier A seed 13's Hertz world, on the stand-in): once
Hertz is added, the surfaces put friction_pp 2.1 sd above its tilt test, so the loop polishes on the
batteries and runs two anchors. A live service cannot be given that world (its stand-in campaigns measure a
material's own tests), so the tests serve the library loop's polish inside a real campaign's report: both
are the same loop's (calibration.machine), and the state is validated against the API's model first.
"""
from __future__ import annotations

from functools import lru_cache


@lru_cache(maxsize=1)
def hertz_report() -> dict:
    """The added effect's iteration's report, as the library loop writes it."""
    from calibration.conditions import standin_conditions
    from calibration.evaluators import StandinEvaluator
    from calibration.loop import CalibrationLoop
    from calibration.testbed import OPTIONS, loop_settings, make_case

    case = make_case(13, "single")
    result = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), loop_settings(case, 3)).run()
    return result.iterations[1].report


def hertz_polish() -> dict:
    """That report's ``polish``, as the API serves it (validated by its model, None fields dropped)."""
    from service.api.responses.report import Polish

    return Polish.model_validate(hertz_report()["polish"]).model_dump(mode="json", exclude_none=True)
