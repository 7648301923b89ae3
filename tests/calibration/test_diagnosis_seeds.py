"""Issue 34, item 2: the diagnosis runs one seed first and the others only where they buy power.

The rule's numbers are its definition (calibration.replicates): a signature is a difference of two battery
means, variance 2 s^2 / m, read against residuals of variance v; one seed suffices below 2 s^2 / v = 1/4.
"""
from __future__ import annotations

import pytest

from calibration import machine, replicates
from calibration.conditions import standin_conditions
from calibration.evaluators import StandinEvaluator
from calibration.localise import ALPHA
from calibration.loop import CalibrationLoop
from calibration.testbed import OPTIONS, loop_settings, make_case
from calibration.vocabulary import RunKind


def _diagnosis(p_leader, verdict="effect indicated", groups=(), indicated=True, p_rest=0.9):
    return {"verdict": verdict, "indicated": ["rolling_epsd2"] if indicated else [],
            "ranking": [{"effect": "rolling_epsd2", "p_holm": p_leader, "alias_group": 1 if groups else None},
                        {"effect": "particle_shape", "p_holm": p_rest, "alias_group": 1 if groups else None}],
            "alias_groups": list(groups)}


def test_the_signature_noise_share_is_two_simulator_variances_over_the_residual_s():
    assert replicates.simulator_share({"a": 1.0, "b": 2.0, "c": 1.0}, {"a": 2.0, "b": 2.0, "c": 1.0}) == pytest.approx(2.0)
    assert replicates.simulator_share({"a": 1.0}, {"a": 2.0}) == pytest.approx(0.5)  # 2 x 1 / 4
    assert replicates.simulator_share({}, {"a": 1.0}) is None


@pytest.mark.parametrize("diagnosis, decided", [
    (_diagnosis(ALPHA / 40), True),                                   # claimed far below alpha / 20
    (_diagnosis(ALPHA / 10), False),                                  # claimed, but not decisively
    (_diagnosis(0.3, verdict="inconclusive", indicated=False), False),
    (_diagnosis(0.6, verdict="inconclusive", indicated=False, p_rest=0.7), True),  # every candidate futile
    ({"verdict": "no misfit", "ranking": []}, True),
    # a rival the evidence has not separated (separation_z below its bound): another seed can separate them
    (_diagnosis(ALPHA / 40, groups=[{"group": 1, "effects": ["rolling_epsd2", "particle_shape"],
                                     "separators": [{"effects": ["rolling_epsd2", "particle_shape"], "separation_z": 1.2}]}]),
     False),
    # collinear signatures (|cos| > 0.9, no separation_z): physics more seeds cannot separate
    (_diagnosis(ALPHA / 40, groups=[{"group": 1, "effects": ["rolling_epsd2", "particle_shape"],
                                     "separators": [{"effects": ["rolling_epsd2", "particle_shape"], "separation_z": None}]}]),
     True),
])
def test_when_one_seed_decides(diagnosis, decided):
    assert (replicates.decided(diagnosis) is not None) is decided


def test_a_close_decision_adds_seeds_only_where_the_simulator_s_scatter_matters():
    close = _diagnosis(ALPHA / 10)
    assert replicates.more_seeds(close, 1.0)[0] is True
    assert replicates.more_seeds(close, None)[0] is True
    more, why = replicates.more_seeds(close, 0.2)
    assert more is False and "measurements' scatter dominates" in why
    assert replicates.more_seeds(_diagnosis(ALPHA / 40), 1.0)[0] is False


def test_the_loop_runs_the_other_seeds_when_the_first_does_not_decide(monkeypatch):
    """Plumbing: forced to find the decision close, the diagnosis adds the second seed's baseline and
    candidates after the first's, and the ranking is made on both."""
    monkeypatch.setattr(replicates, "more_seeds", lambda diagnosis, share: (True, "forced close"))
    case = make_case(7, "single", effects={"rolling_epsd2": 0.3})
    settings = loop_settings(case, diagnose_always=False, automatic=False)
    result = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), settings).run()
    it = result.first
    runs = sorted((r for r in it.runs if r.kind == RunKind.DIAGNOSIS), key=lambda r: r.std_order)
    per_seed = len(runs) // 2
    assert [r.std_order for r in runs] == list(range(1, len(runs) + 1))
    assert len({r.seed for r in runs[:per_seed]}) == 1 and len({r.seed for r in runs[per_seed:]}) == 1
    stages = it.report["diagnosis_stages"]
    assert [s["seeds"] for s in stages] == [1, 2] and stages[0]["more_seeds"] and not stages[1]["more_seeds"]
    assert it.report["diagnosis"]["batteries"] == len(runs)
    assert len(it.report["diagnosis_plan"]) == len(runs)


def test_one_seed_first_halves_a_decided_diagnosis():
    case = make_case(7, "single", effects={"rolling_epsd2": 0.3})  # lambda in the hundreds: decided at once
    counts = {}
    for adaptive in (True, False):
        settings = loop_settings(case, diagnose_always=False, automatic=False, adaptive_replicates=adaptive)
        it = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), settings).run().first
        counts[adaptive] = sum(r.kind == RunKind.DIAGNOSIS for r in it.runs)
        seeds = settings.confirmation_seeds
        assert it.report["diagnosis"]["ranking"][0]["effect"] in ("rolling_epsd2", "particle_shape")
    assert counts[False] == seeds * counts[True]  # a baseline and each candidate, per seed
    assert machine.replicates is replicates



def _ranked(lead_lm, rival_lm, rival_p, rival_noise, rival_gamma=0.2):
    d = _diagnosis(ALPHA / 40, p_rest=rival_p)
    d["ranking"][0].update(lm=lead_lm, gamma=0.3, signature_noise=0.05)
    d["ranking"][1].update(lm=rival_lm, gamma=rival_gamma, signature_noise=rival_noise)
    return d


def test_a_rival_whose_noisy_signature_could_reach_the_leader_keeps_the_ranking_open():
    """Noise attenuates a signature's score, LM_observed ~ LM_true (1 - share): a rival at LM 20 with 70 %
    of its signature noise could stand at 67 > the leader's 60; at 50 % noise only at 40. The ranking is
    then made on every seed, unless the measurements' scatter dominates (share of the simulator below 1/4)."""
    close = _ranked(60.0, 20.0, ALPHA / 2, 0.7)
    more, why = replicates.more_seeds(close, 1.8)
    assert more is True and "ranking is close" in why and "particle_shape" in why
    assert replicates.more_seeds(close, None)[0] is True
    assert replicates.more_seeds(close, 0.2)[0] is False  # one seed's signature is as good as several
    assert replicates.more_seeds(_ranked(60.0, 20.0, ALPHA / 2, 0.5), 1.8)[0] is False  # 40 < 60
    assert replicates.more_seeds(_ranked(60.0, 1.0, ALPHA / 2, 1.2), 1.8)[0] is True    # pure noise
    assert replicates.more_seeds(_ranked(60.0, 20.0, 2 * ALPHA, 0.9), 1.8)[0] is False  # not significant
    assert replicates.more_seeds(_ranked(60.0, 20.0, ALPHA / 2, 0.9, rival_gamma=-0.2), 1.8)[0] is False


def test_the_noise_share_of_a_signature_by_hand():
    """E|M e|^2 / |M s|^2: with M removing the first row's direction, s = (1, 1, 0) projects to (0, 1, 0)
    (length 1) and unit noise in every row leaves 2 after projection; unknown noise counts as none."""
    import numpy as np

    from calibration.attribute import noise_share, signature_noise_var

    M = np.eye(3) - np.outer([1.0, 0, 0], [1.0, 0, 0])
    assert noise_share(M, np.array([1.0, 1.0, 0.0]), np.ones(3)) == pytest.approx(2.0)
    assert noise_share(np.eye(3), np.array([2.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])) == pytest.approx(0.25)
    assert noise_share(M, np.array([1.0, 1.0, 0.0]), None) == 0.0
    # a signature the baseline parameters absorb whole has no length left: whatever noise it has is all of it
    assert noise_share(M, np.array([1.0, 0.0, 0.0]), np.ones(3)) == float("inf")

    class Res:  # two target rows (sd 2 and 4) and one prior row
        keys = ["a", "b"]
        sd = np.array([2.0, 4.0])
        prior_names = ["density"]

    # 2 s_sim^2 / (m sd^2 step^2): row a 2 x 1 / (2 x 4 x 0.25) = 1; row b unknown; the prior row 0
    assert signature_noise_var(Res, {"a": 1.0}, 2, 0.5) == pytest.approx([1.0, 0.0, 0.0])


def test_a_leader_whose_probe_is_mostly_noise_is_not_decided_on_one_seed():
    """A probe whose expected noise is its whole projected length (share >= 1) measured the packing, not the
    effect: its score is a random direction's against the misfit, which the directed test does not price.
    Tier B's weak Hertz world at one seed: cohesion first at LM 13.7, Holm p 0.00044 (< alpha / 20), its probe's
    noise 1.42 of its signature, the simulator's share of the residuals' variance above 1/4. Every seed decides;
    where the measurements' scatter dominates, or the leader's probe is mostly signal, one seed still does."""
    noisy = _ranked(13.7, 1.5, 0.33, 0.11)
    noisy["ranking"][0].update(p_holm=0.00044, signature_noise=1.42)
    more, why = replicates.more_seeds(noisy, 2.3)
    assert more is True and "mostly the simulator's scatter (1.4 of its signature)" in why
    assert replicates.more_seeds(noisy, 0.2)[0] is False
    clear = _ranked(13.7, 1.5, 0.33, 0.11)
    clear["ranking"][0].update(p_holm=0.00044, signature_noise=0.32)  # weak cohesion's own probe, session 35
    assert replicates.more_seeds(clear, 2.3)[0] is False
