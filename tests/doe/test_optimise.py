"""Calibration against targets with a known answer.

Responses come from known closed forms that lie inside the fitted model family
(main effects + two-factor interactions, stiffness on a log scale), plus seeded
noise, so the true parameters are the answer the optimiser must find.
"""
import pytest

from doe import (AnalyticEvaluator, DoeError, LinearConstraint, NonlinearConstraint, Prior, calibrate,
                 fit_responses, make_design, run_design)
from doe.synthetic import FACTORS, NOISE, RESPONSES

TRUE = {"particle_density_kg_m3": 2650.0, "friction_pp": 0.55, "friction_pw": 0.3, "stiffness_n_m": 3e6}


@pytest.fixture(scope="module")
def fits():
    design = make_design(FACTORS, full=True, center_runs=4, seed=42)
    results = run_design(design, AnalyticEvaluator(RESPONSES, NOISE), include_seed=True)
    return fit_responses(design, results)


def targets_at(params):
    return [{"response": r, "value": fn(params), "uncertainty": NOISE[r], "test": "lab", "condition": "c1"}
            for r, fn in RESPONSES.items()]


def test_recovers_known_parameters_within_uncertainty(fits):
    res = calibrate(fits, targets_at(TRUE), seed=1)
    assert res.success
    for name, true in TRUE.items():
        assert abs(res.parameters[name] - true) <= 3 * res.parameter_std[name], name
    for t in res.targets:
        assert abs(t["standardised_residual"]) < 1.0
        assert t["pi_low"] < t["target"] < t["pi_high"]
        assert t["test"] == "lab" and t["condition"] == "c1"
    assert all(r["reachable"] for r in res.reachability)
    assert not res.active_constraints and not res.active_bounds


def test_binding_constraint_is_honoured_and_reported(fits):
    truth = dict(TRUE, friction_pp=0.3, friction_pw=0.45)     # violates friction_pw <= friction_pp
    res = calibrate(fits, targets_at(truth), constraints=["friction_pw <= friction_pp"], seed=1)
    p = res.parameters
    assert p["friction_pw"] <= p["friction_pp"] + 1e-8
    assert res.active_constraints == ["friction_pw <= friction_pp"]
    assert res.constraints[0]["active"] and res.objective > 1.0
    free = calibrate(fits, targets_at(truth), seed=1)
    assert free.parameters["friction_pw"] > free.parameters["friction_pp"]


def test_out_of_reach_target_is_flagged(fits):
    tg = targets_at(TRUE)
    tg[0] = dict(tg[0], value=2500.0)       # max bulk density in the box is 0.6*3000*0.99 = 1782
    res = calibrate(fits, tg, seed=1)
    reach = {r["response"]: r for r in res.reachability}
    assert not reach["bulk_density_kg_m3"]["reachable"]
    assert reach["bulk_density_kg_m3"]["min_standardised_misfit"] > 3
    assert all(reach[r]["reachable"] for r in RESPONSES if r != "bulk_density_kg_m3")
    assert res.unreachable[0]["response"] == "bulk_density_kg_m3"
    assert {"parameter": "particle_density_kg_m3", "side": "high"}.items() <= res.active_bounds[0].items()


def test_prior_fixed_nonlinear_and_determinism(fits):
    tg = [t for t in targets_at(TRUE) if t["response"] != "bulk_density_kg_m3"]
    prior = Prior("particle_density_kg_m3", 2400, 10, "water displacement")
    res = calibrate(fits, tg, priors=[prior], fixed={"stiffness_n_m": 3e6},
                    constraints=[NonlinearConstraint(lambda p: p["friction_pp"] ** 2, upper=0.36, name="pp^2")],
                    seed=4)
    assert res.parameters["particle_density_kg_m3"] == pytest.approx(2400, abs=1)
    assert res.parameters["stiffness_n_m"] == 3e6 and res.parameter_std["stiffness_n_m"] == 0.0
    assert res.parameters["friction_pp"] ** 2 <= 0.36 + 1e-8
    again = calibrate(fits, tg, priors=[prior], fixed={"stiffness_n_m": 3e6},
                      constraints=[NonlinearConstraint(lambda p: p["friction_pp"] ** 2, upper=0.36)], seed=4)
    assert again.parameters == res.parameters


def test_design_region_unless_extrapolation_allowed(fits):
    tg = targets_at(TRUE)
    with pytest.raises(DoeError, match="leaves the design region"):
        calibrate(fits, tg, bounds={"friction_pp": (0.1, 0.9)})
    res = calibrate(fits, tg, bounds={"friction_pp": (0.1, 0.9)}, allow_extrapolation=True, seed=0)
    assert res.allow_extrapolation and res.success
    with pytest.raises(DoeError, match="unknown parameter"):
        calibrate(fits, tg, fixed={"nonsense": 1})
    with pytest.raises(DoeError, match="no fitted model"):
        calibrate(fits, [{"response": "x", "value": 1, "uncertainty": 1}])
    with pytest.raises(DoeError, match="uncertainty"):
        calibrate(fits, [{"response": "friction_angle_deg", "value": 1, "uncertainty": 0}])


def test_linear_constraint_objects_and_text_agree(fits):
    tg = targets_at(dict(TRUE, friction_pp=0.3, friction_pw=0.45))
    a = calibrate(fits, tg, constraints=[LinearConstraint({"friction_pw": 1, "friction_pp": -1}, upper=0)], seed=1)
    b = calibrate(fits, tg, constraints=[{"expression": "friction_pw - friction_pp <= 0"}], seed=1)
    assert a.parameters == pytest.approx(b.parameters)
    import json
    json.dumps(a.to_dict())


def test_too_few_targets_say_parameters_are_not_identified(fits):
    res = calibrate(fits, targets_at(TRUE)[:1], seed=0)
    assert res.success and abs(res.targets[0]["standardised_residual"]) < 1e-3
    assert all(v is None for v in res.parameter_std.values())
    assert res.notes and "do not identify" in res.notes[0]
