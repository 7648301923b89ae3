"""The heart of demcal on data with a hidden effect: where the model fails, which effect is
missing, what it could be confused with, which measurement separates them, and the error falling
once it is added. The "measurements" come from another world (perturbed constants and saturation
law) than the model under test, with laboratory scatter (calibration.testbed)."""
import dataclasses

import pytest

from calibration.conditions import standin_conditions
from calibration.evaluators import StandinEvaluator
from calibration.loop import CalibrationLoop
from calibration.records import Measured
from calibration.testbed import OPTIONS, loop_settings, make_case


def _loop(case, targets=None, **settings):
    """The testbed's loop (automatic mode) with the diagnosis only where the report asks for one."""
    return CalibrationLoop(case.targets if targets is None else targets, StandinEvaluator(standin_conditions(OPTIONS)),
                           loop_settings(case, **{"diagnose_always": False, **settings}))


@pytest.fixture(scope="module")
def rolling():
    case = make_case(7, "single", effects={"rolling_epsd2": 0.3})
    loop = _loop(case)
    return case, loop, loop.run()


def test_where_the_model_fails(rolling):
    case, loop, result = rolling
    report = result.first.report
    assert result.model_fails(result.first) and report["lack_of_fit"]["p_value"] < 0.05
    # missing rolling resistance is a strength deficit: the shear test carries a significant share
    dst = next(t for t in report["tests"] if t["test"] == "dst")
    assert dst["fails"] and dst["share"] > 0.2
    # ... and the friction saturates: mu_pp pinned at the top of its range pushing higher, or the
    # pycnometer density pulled (spheres pack too densely), the design note's G1 symptoms
    conflicts = report["conflicts"]
    assert any(b["parameter"] == "friction_pp" and b["pushes"] == "higher" for b in conflicts["active_bounds"]) \
        or conflicts["priors_pulled"]
    assert {"modulus_log_slope", "shear_stress", "dilatancy"} <= set(report["trends"])


def test_which_effect_what_it_is_confused_with_and_what_separates_them(rolling):
    case, loop, result = rolling
    att = result.diagnosis(1)
    assert att["verdict"] == "effect indicated"
    top = att["ranking"][0]
    assert top["effect"] in ("rolling_epsd2", "particle_shape")
    group = next(g for g in att["alias_groups"] if top["effect"] in g["effects"])
    assert set(group["effects"]) >= {"rolling_epsd2", "particle_shape"}
    assert group["separators"][0]["separating_measurement"].startswith(("dst", "fill", "aor", "anchor", "cct"))
    assert att["fingerprints"]["effects"]["rolling_epsd2"]["friction_angle"] == "+"
    assert att["fingerprints"]["observed"]["friction_angle"] == "+"
    hertz = next(r for r in att["ranking"] if r["effect"] == "hertz_mindlin")
    assert hertz["p_holm"] > 0.05          # no stress-dependence of E' was hidden: Hertz is not named


def test_adding_the_effect_makes_the_error_fall(rolling):
    case, loop, result = rolling
    decision = result.decisions[0]
    assert decision["accepted"] and decision["effect"] in ("rolling_epsd2", "particle_shape")
    before, after = result.first.report["lack_of_fit"], result.final.report["lack_of_fit"]
    assert after["statistic"] < 0.5 * before["statistic"]
    # the loop stops because the lack of fit passes (a test failing its own check is said after it)
    assert result.stop_reason.startswith("lack of fit passes")
    history = result.history()["iterations"]
    assert [h["number"] for h in history][:2] == [1, 2] and history[1]["added_effect"] == [decision["effect"]]


def test_no_misfit_no_effect():
    case = make_case(3, "null")
    result = _loop(case).run()
    assert not result.model_fails(result.first)
    assert result.decisions == [] and result.stop_reason == "lack of fit passes"


def test_diagnose_always_asks_the_directed_test_and_still_adds_nothing_to_a_true_model():
    case = make_case(3, "null")
    result = _loop(case, diagnose_always=True).run()
    assert result.diagnosis(1) is not None and len(result.iterations) == 1
    adequacy = result.first.report["adequacy"]
    assert adequacy["directed"] is not None and not adequacy["fails"]
    assert result.decisions == [] and result.stop_reason == "lack of fit passes"


def test_a_physically_impossible_measurement_is_not_blamed_on_physics():
    # a bulk density above the particle density (porosity < 0): every candidate loosens the packing, none
    # can explain a density the pycnometer forbids, so the diagnosis points at the measurement
    case = make_case(3, "null")
    targets = [dataclasses.replace(t, values=tuple(1.5 * v for v in t.values))
               if t.key.quantity == "bulk_density_kg_m3" else t for t in case.targets]
    result = _loop(case, targets, automatic=False).run()
    assert result.model_fails(result.first)
    att = result.diagnosis(1)
    assert att["verdict"] == "no physical match"
    assert any("bulk_density" in m for m in att["measure_next"])
    assert all(isinstance(t, Measured) for t in targets)


def test_the_loop_on_a_registered_backend_runs_the_targets_conditions_and_finds_the_effect():
    """``CalibrationLoop.on_backend`` runs the batteries a campaign would queue: the targets' DST loads and
    E' stresses (the test bed measures at loads other than the battery's defaults), so every target is
    simulated, and the hidden rolling resistance is named and added as through the stand-in itself."""
    case = make_case(7, "single", effects={"rolling_epsd2": 0.3})
    settings = loop_settings(case, diagnose_always=False, options={"include_aor": True, "include_anchor": True})
    loop = CalibrationLoop.on_backend(case.targets, "analytic", settings)
    assert loop.evaluator.options["dst_normal_stresses_pa"] == OPTIONS["dst_normal_stresses_pa"]
    assert loop.evaluator.options["cct_window_stresses_pa"] == OPTIONS["cct_window_stresses_pa"]
    result = loop.run()
    first = result.first.report
    assert all(t["status"] == "modelled" for t in first["targets"])
    assert result.decisions and result.decisions[0]["accepted"]
    assert result.decisions[0]["effect"] in ("rolling_epsd2", "particle_shape")
