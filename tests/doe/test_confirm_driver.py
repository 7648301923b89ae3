"""Evaluator-agnostic driver and confirmation with a proposed next design."""
import numpy as np
import pytest

from doe import AnalyticEvaluator, DoeError, calibrate, fit_responses, make_design, run_design
# the function, by its module: once doe.confirm (the module) is imported, `doe.confirm` names the module
from doe.confirm import confirm

FACTORS = [("x1", 0.0, 1.0), ("x2", 10.0, 20.0)]


def test_run_design_maps_run_order_back_to_std_order():
    d = make_design(FACTORS, center_runs=3, seed=9)
    seen = []

    def evaluator(batch):
        seen.extend(batch)
        return [{"y": p["x1"] + 100 * p["x2"]} for p in batch]

    res = run_design(d, evaluator, batch_size=2)
    assert seen == d.parameter_sets("run")                  # executed in randomised run order
    for row, r in zip(d.records("std"), res):                # returned in standard order
        assert r["y"] == pytest.approx(row["x1"] + 100 * row["x2"])
    with pytest.raises(DoeError, match="returned 0 results"):
        run_design(d, lambda batch: [])


def test_centre_replicates_with_distinct_seeds_give_pure_error():
    d = make_design(FACTORS, center_runs=4, seed=1)
    ev = AnalyticEvaluator({"y": lambda p: 3 * p["x1"]}, {"y": 0.1})
    res = run_design(d, ev, include_seed=True)
    centre = [r["y"] for r, c in zip(res, d.center_mask) if c]
    assert len(set(centre)) == 4                             # seed-to-seed scatter
    again = run_design(d, AnalyticEvaluator({"y": lambda p: 3 * p["x1"]}, {"y": 0.1}), include_seed=True)
    assert again == res                                      # same seeds, same values
    fit = fit_responses(d, res)["y"]
    pe = fit.anova_row("Pure Error")
    assert pe.df == 3 and pe.sum_of_squares == pytest.approx(np.sum((np.array(centre) - np.mean(centre)) ** 2))


def _setup(truth, sd=0.05, seed=3):
    d = make_design(FACTORS, center_runs=4, seed=seed)
    ev = AnalyticEvaluator({"y": truth}, {"y": sd})
    fits = fit_responses(d, run_design(d, ev, include_seed=True))
    return d, fits


def test_confirmation_inside_prediction_interval():
    truth = lambda p: 1 + 2 * p["x1"] + 0.1 * p["x2"]  # noqa: E731  inside the model family
    d, fits = _setup(truth)
    cal = calibrate(fits, [{"response": "y", "value": 3.5, "uncertainty": 0.05}], seed=0)
    res = confirm(fits, cal.parameters, {"y": truth(cal.parameters)})
    assert res.confirmed and res.next_design is None and res.responses[0]["inside"]


def test_curvature_leads_to_ccd_augmentation():
    truth = lambda p: 5 * (p["x1"] - 0.5) ** 2 + 0.1 * p["x2"]  # noqa: E731  curved
    d, fits = _setup(truth)
    assert fits["y"].curvature_row.p_value < 0.05
    params = {"x1": 0.5, "x2": 15.0}
    res = confirm(fits, params, {"y": truth(params)})
    assert not res.confirmed and res.next_design_kind == "augment_ccd"
    nd = res.next_design
    assert sum(t == "axial" for t in nd.point_type) == 4 and nd.n_runs > d.n_runs
    assert res.to_dict()["next_design"]["n_runs"] == nd.n_runs


def test_miss_without_curvature_leads_to_narrowed_factorial():
    truth = lambda p: 1 + 2 * p["x1"] + 0.1 * p["x2"]  # noqa: E731
    d, fits = _setup(truth)
    params = {"x1": 0.9, "x2": 12.0}
    res = confirm(fits, params, {"y": truth(params) + 1.0})  # far outside the interval
    assert res.next_design_kind == "narrowed_factorial"
    nd = res.next_design
    x1, x2 = nd.factor("x1"), nd.factor("x2")
    assert (x1.low, x1.high) == pytest.approx((0.5, 1.0))   # half range, shifted to stay inside the box
    assert (x2.low, x2.high) == pytest.approx((10.0, 15.0))
    assert nd.center_mask.sum() == 3
