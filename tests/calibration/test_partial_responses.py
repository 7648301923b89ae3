"""A target some design batteries lack (a hold that did not settle at a stiff corner) is still modelled.

The truth is a linear response in the coded factors with one interaction (as tests/doe/test_missing.py);
the first battery of the design lacks it, as do three more at the corners the hold lost.
"""
import numpy as np

from calibration.fitting import fit_targets
from calibration.records import Measured
from calibration.keys import ResponseKey
from doe import fractional_factorial

FACTORS = [("a", 0.0, 2.0), ("b", 0.0, 2.0), ("c", 0.0, 2.0), ("d", 0.0, 2.0), ("e", 0.0, 2.0)]
CONDITION = {"normal_stress_pa": 3000.0}


def _records(design):
    rng = np.random.default_rng(5)
    runs = []
    lost = {0} | {i for i in range(design.n_runs) if design.coded[i, 4] > 0.5 and design.coded[i, 0] > 0.5}
    lost = sorted(lost)[:4]
    for i, x in enumerate(design.coded):
        density = 1500.0 + 40.0 * x[0] + rng.normal(0.0, 2.0)
        e_ur = 8.0e6 + 2.0e6 * x[4] - 1.0e6 * x[1] + 0.8e6 * x[1] * x[4] + 0.5e6 * x[2] + rng.normal(0.0, 5e4)
        run = [{"test": "fill", "quantity": "bulk_density_kg_m3", "condition": {}, "value": density}]
        if i not in lost:
            run.append({"test": "cct", "quantity": "unload_reload_modulus_pa", "condition": CONDITION,
                        "value": e_ur})
        runs.append(run)
    return runs, lost


def test_a_target_the_first_battery_lacks_is_matched_and_modelled_on_the_rest():
    design = fractional_factorial(FACTORS, ["E=ABCD"], center_runs=3, seed=1)
    runs, lost = _records(design)
    assert lost[0] == 0 and len(lost) == 4
    target = Measured(ResponseKey.from_record({"test": "cct", "quantity": "unload_reload_modulus_pa",
                                               "condition": CONDITION}), (8.1e6,), "Pa", 2e5)
    (model,) = fit_targets(design, runs, [target])
    assert model.status == "modelled"
    assert model.fit.n == design.n_runs - 4
    est = dict(zip(["1"] + model.fit.term_labels, model.fit.params))
    # the true coded coefficients, within 4 standard errors of the true noise (5e4 Pa)
    se = dict(zip(["1"] + model.fit.term_labels, 5e4 * np.sqrt(np.diag(model.fit.ols.normalized_cov_params))))
    for name, value in {"1": 8.0e6, "E": 2.0e6, "B": -1.0e6, "BE": 0.8e6, "C": 0.5e6}.items():
        assert abs(est[name] - value) < 4 * se[name], name
    assert "4 of 19 runs have no value" in model.to_dict()["fit"]["reduction_log"][0]
