"""A box drawn too narrow is widened before physics is blamed (calibration.decisions.widened_box,
calibration.analysis.diagnosis_projection, calibration.automatic.box_widening).

The case: a stand-in world with no hidden effect whose contact stiffness lies above the stiffness box the
user drew (its top at 0.75 x the truth). The optimum pins the stiffness at the top, E' comes out low and the
lack of fit fails. Before session 23 the loop stopped there ("diagnosis: inconclusive", the misfit "in cct
confined_modulus_pa"); a candidate that raises E' could as well have been named. Now the diagnosis counts
the pinned stiffness as absorbing (its typical range runs to 1e10 N/m), names nothing, and the same model
runs again in a box the box's width wider, where the truth lies and the fit passes.
"""
import pytest

from calibration.conditions import standin_conditions
from calibration.evaluators import StandinEvaluator
from calibration.loop import CalibrationLoop
from calibration.testbed import FACTORS, OPTIONS, loop_settings, make_case

STIFFNESS = "particle_stiffness_n_per_m"


def test_a_stiffness_box_below_the_truth_is_widened_and_no_effect_is_added():
    case = make_case(3, "null")
    truth = case.truth[STIFFNESS]
    factors = [dict(f, low=0.5e6, high=0.75 * truth) if f["name"] == STIFFNESS else dict(f) for f in FACTORS]
    settings = loop_settings(case, 3, factors=factors, diagnose_always=False)
    result = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), settings).run()

    first, second = result.iterations
    pinned = {b["parameter"]: b["side"] for b in first.report["conflicts"]["active_bounds"]}
    assert pinned.get(STIFFNESS) == "high" and first.report["lack_of_fit"]["p_value"] < 0.05
    assert first.report["diagnosis"]["indicated"] == []
    record = first.report["automatic"]
    assert record["next_effect"] is None and record["stop_reason"] is None
    # the box's width more on the pinned side: 0.75 truth + (0.75 truth - 0.5e6), above the truth for truth > 1e6
    (widened,) = record["widened_box"]
    assert (widened["parameter"], widened["side"]) == (STIFFNESS, "high")
    assert (widened["from"], widened["to"]) == pytest.approx((0.75 * truth, 1.5 * truth - 0.5e6))
    box = next(f for f in second.parameters["factors"] if f["name"] == STIFFNESS)
    assert box["low"] == 0.5e6 and box["high"] > truth
    assert not second.parameters.get("effects") and result.decisions == []
    assert result.stop_reason == "lack of fit passes"
    assert result.history()["iterations"][1]["box_widened"] == [STIFFNESS]
