"""A completed automatic loop taken up again (machine.extended, CalibrationLoop.extend): the iteration limit
is a budget, so a loop stopped by it goes on where it stopped, as if the limit had been higher from the
start, and a loop stopped for any other reason is not set going again."""
import pytest

from calibration.conditions import standin_conditions
from calibration.errors import SettingsError
from calibration.evaluators import StandinEvaluator
from calibration.loop import CalibrationLoop
from calibration.settings import MAX_ITERATIONS
from calibration.testbed import OPTIONS, loop_settings, make_case
from calibration.vocabulary import StopReason


def _loop(case, **settings):
    evaluator = StandinEvaluator(standin_conditions(OPTIONS))
    return CalibrationLoop(case.targets, evaluator, loop_settings(case, **{"diagnose_always": False, **settings})), evaluator


@pytest.fixture(scope="module")
def rolling():
    """Rolling resistance hidden at 0.3 (lambda in the hundreds on the stand-in): the first iteration's
    diagnosis indicates an effect, which a limit of one iteration leaves unadded."""
    return make_case(7, "single", effects={"rolling_epsd2": 0.3})


def test_a_loop_stopped_by_its_limit_goes_on_as_if_the_limit_had_been_higher(rolling):
    stopped, first_runs = _loop(rolling, max_iterations=1)
    result = stopped.run()
    assert result.stop_reason == StopReason.MAX_ITERATIONS and len(result.iterations) == 1
    indicated = result.diagnosis(1)["indicated"]
    assert indicated, "the case must leave an effect to add when the limit stops the loop"

    continued = stopped.extend(1).run()
    whole, _ = _loop(rolling, max_iterations=2)
    straight = whole.run()
    assert [it.number for it in continued.iterations] == [1, 2] == [it.number for it in straight.iterations]
    # the first iteration's record now says what the loop had stopped for, and what it did instead
    record = continued.first.report["automatic"]
    assert record["continued"] == {"more_iterations": 1, "max_iterations": 2, "stopped_for": StopReason.MAX_ITERATIONS}
    assert record["next_effect"] == straight.first.report["automatic"]["next_effect"] == indicated[0]
    # the second iteration is the one an uninterrupted loop runs: same design seeds, same batteries, same fit
    a, b = continued.final.report, straight.final.report
    assert a["optimum"] == b["optimum"]
    assert a["lack_of_fit"]["statistic"] == pytest.approx(b["lack_of_fit"]["statistic"], rel=1e-12)
    assert continued.stop_reason == straight.stop_reason
    # and the error falls as it does there (the heart's promise survives the interruption)
    assert continued.final.report["lack_of_fit"]["statistic"] < 0.5 * continued.first.report["lack_of_fit"]["statistic"]


def test_a_loop_that_stopped_for_its_answer_is_not_set_going_again():
    null = make_case(3, "null")
    loop, evaluator = _loop(null)
    result = loop.run()
    assert result.stop_reason == StopReason.PASSES
    runs = evaluator.runs
    with pytest.raises(SettingsError) as refused:
        loop.extend(1)
    assert refused.value.conflict and refused.value.field == "more_iterations"
    assert "lack of fit passes" in refused.value.message
    # refused means untouched: still complete, no battery run, the record as it was
    assert loop.state.complete and evaluator.runs == runs and loop.result().stop_reason == StopReason.PASSES
    assert "continued" not in loop.state.iterations[-1].report["automatic"]


def test_the_limit_stays_a_limit(rolling):
    loop, _ = _loop(rolling, max_iterations=1)
    loop.run()
    with pytest.raises(SettingsError) as refused:
        loop.extend(MAX_ITERATIONS)
    assert refused.value.field == "more_iterations" and not refused.value.conflict
    assert f"at most {MAX_ITERATIONS - 1} more" in refused.value.message


def test_a_loop_still_running_or_not_automatic_is_refused(rolling):
    running, _ = _loop(rolling, max_iterations=1)
    running.advance()
    with pytest.raises(SettingsError, match="has not stopped"):
        running.extend(1)
    manual, _ = _loop(rolling, automatic=False)
    manual.run()
    with pytest.raises(SettingsError, match="only an automatic loop") as refused:
        manual.extend(1)
    assert refused.value.field == "automatic"
