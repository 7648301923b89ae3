"""The held-out confirmation after a polish that took a step (``calibration.polish.hold_out``).

The steps keep whichever trial's batteries fit best, so read on those batteries the fit looks better than it is.
The report reads the chosen point at fresh seeds instead, and judges there only what no parameter change absorbs
(``Residuals.judged``). The first test checks that rule against its analytic null on a linear Gaussian model; the
others run the loop in the stand-in world of ``test_polish_prior`` (tier A's seed 13, Hertz-Mindlin hidden), where
the added effect's iteration polishes.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats as sps

from calibration import polish
from calibration.conditions import standin_conditions
from calibration.evaluators import StandinEvaluator
from calibration.loop import CalibrationLoop
from calibration.stats import lack_of_fit, residual_maker
from calibration.testbed import OPTIONS, loop_settings, make_case


def test_held_out_residuals_projected_keep_the_lack_of_fit_s_null_and_raw_ones_do_not():
    """Whitened linear model: measurements d = e (variance share u_i per row), batteries at theta J theta + eta
    (share s_i = 1 - u_i, fresh at every set of seeds). theta is fitted by least squares on one set (the polish's),
    and the residual read on another: r = e - eta_new - J theta_hat. Analytically (P = J J^+, M = I - P)
    E|r|^2 = tr(M D_u) + tr(D_s) + tr(P D_s), above the n - p the lack of fit assumes, while M r has covariance
    M (D_u + D_s) M = M: E|M r|^2 = n - p, and the chi2(n - p) test keeps its 5 % size."""
    rng = np.random.default_rng(20261207)
    n, p, draws = 14, 4, 20000
    J = rng.standard_normal((n, p))
    share_sim = rng.uniform(0.3, 0.9, n)
    M = residual_maker(J)
    P = np.eye(n) - M
    e = rng.standard_normal((draws, n)) * np.sqrt(1.0 - share_sim)
    eta_old = rng.standard_normal((draws, n)) * np.sqrt(share_sim)
    eta_new = rng.standard_normal((draws, n)) * np.sqrt(share_sim)
    theta_hat = np.linalg.lstsq(J, (e - eta_old).T, rcond=None)[0].T
    r = e - eta_new - theta_hat @ J.T
    projected = r @ M  # M is symmetric
    raw_sq, projected_sq = np.sum(r * r, axis=1), np.sum(projected * projected, axis=1)
    expected_raw = np.trace(M * (1.0 - share_sim)) + share_sim.sum() + np.trace(P * share_sim)
    se = lambda x: x.std() / np.sqrt(draws)  # noqa: E731
    assert abs(raw_sq.mean() - expected_raw) < 4 * se(raw_sq)
    assert abs(projected_sq.mean() - (n - p)) < 4 * se(projected_sq)
    assert expected_raw > n - p + 1.0  # the inflation the projection removes is not small here
    critical = sps.chi2.isf(0.05, n - p)
    size_raw, size_projected = np.mean(raw_sq > critical), np.mean(projected_sq > critical)
    print(f"\nheld-out residuals, {draws} draws: chi2({n - p}) test rejects raw {size_raw:.3f}, "
          f"projected {size_projected:.3f} (nominal 0.05)")
    assert abs(size_projected - 0.05) < 4 * np.sqrt(0.05 * 0.95 / draws)
    assert size_raw > 0.10
    # the module's own test on one draw agrees with chi2(n - p) on the projected residuals
    one = lack_of_fit(projected[0], M, np.full(n, np.inf))
    assert one.dof == n - p and one.p_value == pytest.approx(sps.chi2.sf(projected_sq[0], n - p))


def _run(holdout: bool):
    case = make_case(13, "single")
    settings = loop_settings(case, 3).model_copy(update={"polish_holdout": holdout})
    return settings, CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), settings).run()


@pytest.fixture(scope="module")
def both():
    return _run(True), _run(False)


def test_after_a_step_the_report_reads_the_chosen_point_at_fresh_seeds(both):
    (settings, result), _ = both
    added = result.iterations[1]
    state = added.optimum["polish"]
    assert state["steps"] >= 1 and state["stage"] == "done"
    held = state["holdout_seeds"]
    m = settings.confirmation_seeds
    assert len(held) == m
    # fresh: no other battery of the iteration ran at these seeds
    others = {r.seed for r in added.runs if r.id not in state["run_ids"]}
    assert not set(held) & others
    runs = polish.final_runs(added)
    assert [r.seed for r in runs] == held and all(r.natural == pytest.approx(state["theta"]) for r in runs)
    assert added.report["confirmation_seeds"] == held
    summary = added.report["polish"]
    assert summary["holdout_seeds"] == held and summary["seeds"] == state["seeds"]
    assert summary["holdout_chi2"] is not None
    # the held-out round's batteries are counted with the polish's
    assert summary["batteries"] == sum(1 for r in added.runs if r.kind == "polish")
    # the diagnosis's signatures are measured at seeds of their own, derived from the seeds the report read
    for r in added.runs:
        if r.kind == "diagnosis":
            assert r.seed not in held and r.seed not in state["seeds"]


def test_the_iteration_that_did_not_step_runs_no_held_out_round(both):
    (_, result), _ = both
    for it in result.iterations:
        state = (it.optimum or {}).get("polish") or {}
        if not polish.moved(state):
            assert "holdout_seeds" not in state


def test_without_the_held_out_round_the_report_reads_the_polish_s_own_batteries(both):
    (settings, with_holdout), (_, without) = both
    added = without.iterations[1]
    state = added.optimum["polish"]
    assert state["steps"] >= 1 and "holdout_seeds" not in state
    assert added.report["confirmation_seeds"] == state["seeds"]
    held = with_holdout.iterations[1]
    # the same polish, one round of confirmation_seeds batteries apart
    assert held.optimum["polish"]["theta"] == pytest.approx(state["theta"])
    n_polish = lambda it: sum(1 for r in it.runs if r.kind == "polish")  # noqa: E731
    assert n_polish(held) == n_polish(added) + settings.confirmation_seeds


def test_measured_points_leave_the_held_out_round_out():
    """The intervals' likelihood ratio compares points measured at the polish's own seeds; the held-out round (the
    chosen point again at other seeds) is not another section of the objective (``polish.measured_points``)."""
    from types import SimpleNamespace as NS

    from calibration.awaiting import ROUND

    seeds, held = [11, 12], [91, 92]
    state = {"seeds": seeds, "holdout_seeds": held, "holdout_round": 2, "round": 2, "stage": "done"}
    conf = [NS(kind="confirmation", std_order=k, seed=s, natural={"a": 0.0}, responses={"x": 1}) for k, s in enumerate(seeds)]
    step = [NS(kind="polish", std_order=ROUND + k + 1, seed=s, natural={"a": 0.1}, responses={"x": 1})
            for k, s in enumerate(seeds)]
    out = [NS(kind="polish", std_order=2 * ROUND + k + 1, seed=s, natural={"a": 0.1}, responses={"x": 1})
           for k, s in enumerate(held)]
    points = polish.measured_points(state, conf + step + out)
    assert [p[0] for p in points] == [{"a": 0.0}, {"a": 0.1}]
    assert [[r.seed for r in p[1]] for p in points] == [seeds, seeds]
