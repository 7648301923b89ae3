"""The directed test keeps its size when the simulator is chaotic.

On the DEM engine a candidate's battery and the optimum's at the same seed drift apart, so common
random numbers cancel little of their noise. A signature measured against the confirmation batteries
then shares their noise with the residuals (with the opposite sign), every candidate seems to explain
the residual, and a true model is rejected (the tier-B null: directed p 0.001). The diagnosis measures
signatures against a baseline of its own at other seeds (``attribute.signature_seeds``); here, on true
models whose "simulator" draws independent noise for every parameter set even at one seed (the worst
case of chaos) and scatters five times the stand-in's (so that, as on the DEM engine, the simulator's
scatter outweighs the laboratory's), the combined test must reject at about its nominal 5 %. Measured
on these 100 cases: 6 % with signatures at seeds of their own, 22 % against the confirmation seeds.
Session 41: where the polish took a step, the report reads the chosen point at held-out seeds; judged on the
raw held-out residuals the test rejected 11 %, on the part no parameter absorbs (``Residuals.judged``) 7 %,
and on the polish's own batteries (no held-out round) 2 %: there the choice among noisy trials flattered the fit.
"""
import pytest

from calibration.conditions import standin_conditions
from calibration.evaluators import StandinEvaluator
from calibration.loop import CalibrationLoop
from calibration.testbed import OPTIONS, loop_settings, make_case


@pytest.mark.slow
def test_directed_test_keeps_its_size_on_a_chaotic_simulator():
    n, false_alarms = 100, 0
    for seed in range(n):
        case = make_case(1000 + seed, "null")
        loop = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS), noise_scale=5.0, chaotic=True),
                               loop_settings(case, max_iterations=2, diagnose_always=True))
        result = loop.run()
        assert result.diagnosis(1) is not None
        false_alarms += result.model_fails(result.first)
    rate = false_alarms / n
    print(f"\nchaotic simulator, {n} true models: the combined test rejects {rate:.3f} (nominal 0.05)")
    # binomial(100, 0.05): P(X >= 11) = 0.011
    assert false_alarms <= 10, rate
