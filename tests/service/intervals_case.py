"""A report's intervals with a trade, as the loop writes them, for the page's test.

The case is tier A seed 11 (the stand-in, rolling resistance hidden): once rolling is added, friction_pp and the
rolling friction trade (correlation beyond 0.9), and the report names the pair. A point measured on the batteries
along the trade, beyond the surfaces' interval but within the likelihood ratio's threshold, is then given to
``calibration.intervals.widen_to_measured`` as a polish would, so the page shows an interval widened too. The
intervals are validated against the API's model first, as the API would serve them.
"""
from __future__ import annotations

from functools import lru_cache
from types import SimpleNamespace


@lru_cache(maxsize=1)
def trading_intervals() -> dict:
    from calibration.conditions import standin_conditions
    from calibration.evaluators import StandinEvaluator
    from calibration.intervals import widen_to_measured
    from calibration.loop import CalibrationLoop
    from calibration.testbed import OPTIONS, loop_settings, make_case
    from service.api.responses.report import Intervals

    case = make_case(11, "single")
    result = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), loop_settings(case, 3)).run()
    it = result.iterations[1]
    intervals = it.report["intervals"]
    assert intervals["trades"], "the case's trade is what the page is tested on"
    boxes = {f["name"]: SimpleNamespace(low=f["low"], high=f["high"]) for f in it.parameters["factors"]}
    design = SimpleNamespace(factor=lambda name: boxes[name])
    theta = {name: row["value"] for name, row in intervals["parameters"].items()}
    # a point half way from the interval's end to the box's, on the side with the more room, within the threshold
    name = intervals["trades"][0]["parameters"][0]
    row, box = intervals["parameters"][name], boxes[name]
    side = "low" if row["low"] - box.low > box.high - row["high"] else "high"
    point = dict(theta, **{name: (row[side] + getattr(box, side)) / 2})
    threshold = intervals["scale"] * intervals["quantile"] ** 2
    widened = widen_to_measured(intervals, design, theta, 10.0, [(point, 10.0 + threshold / 2)])
    assert widened["measured_points"]["widened"] == [name]
    return Intervals.model_validate(widened).model_dump(mode="json", exclude_none=True)
