"""A candidate the secant step saw but could not name is probed again at its plausible top
(calibration.attribute.top_probes, calibration.analysis.top_probe_plan): which candidates qualify, the score read
from the better probe with its p Bonferroni over both, worked by hand on signatures of known direction, and the
loop's plumbing (the stage, the plan's entries, the pairing with the baseline at the same seeds)."""
import math

import numpy as np
import pytest
from scipy import stats as sps

from calibration import attribute as attribute_mod
from calibration import stats
from calibration.attribute import STEP, TOP, Signature, attribute, top_probes
from calibration.conditions import standin_conditions
from calibration.evaluators import StandinEvaluator
from calibration.localise import ALPHA, Localisation
from calibration.loop import CalibrationLoop
from calibration.testbed import OPTIONS, loop_settings, make_case
from calibration.vocabulary import DiagnosisVerdict, RunKind
from engine.candidates import candidates


def test_only_strength_type_candidates_whose_top_lies_two_steps_out_get_a_second_probe():
    table = candidates()
    assert table["cohesion_adhesive"].top_step == pytest.approx(200.0)   # 200 J/m2 >= 2 x 60
    assert table["rolling_epsd2"].top_step == pytest.approx(0.5)          # 0.5 >= 2 x 0.15
    assert table["particle_shape"].top_step is None                       # 2.0 - 1.0 = 1.0 < 2 x 0.6
    assert table["hertz_mindlin"].top_step is None                        # a switch: its matched strength only


def _row(effect, p_holm, gamma=1.0, explained=0.1):
    return {"effect": effect, "p_holm": p_holm, "gamma": gamma, "explained": explained}


def _diagnosis(rows, fails=True, indicated=()):
    return {"ranking": rows, "indicated": list(indicated), "adequacy": {"fails": fails}}


def test_which_candidates_are_probed_at_their_top():
    rows = [_row("rolling_epsd2", 1e-6, explained=0.28), _row("cohesion_adhesive", 1e-4, explained=0.18),
            _row("particle_shape", 1e-3), _row("hertz_mindlin", 1e-3)]
    # seen (Holm-significant, positive) but not named, with a top two steps out: rolling and cohesion
    assert top_probes(_diagnosis(rows)) == ["rolling_epsd2", "cohesion_adhesive"]
    assert top_probes(_diagnosis(rows), probed={"rolling_epsd2"}) == ["cohesion_adhesive"]  # once each
    # not seen, pointing the other way, or explaining enough already: no second probe
    assert top_probes(_diagnosis([_row("cohesion_adhesive", 0.2)])) == []
    assert top_probes(_diagnosis([_row("cohesion_adhesive", 1e-4, gamma=-5.0)])) == []
    assert top_probes(_diagnosis([_row("cohesion_adhesive", 1e-4, explained=0.5)])) == []
    # a model within the noise, or one whose diagnosis names an effect, needs none
    assert top_probes(_diagnosis(rows, fails=False)) == []
    assert top_probes(_diagnosis(rows, indicated=["rolling_epsd2"])) == []


def test_the_better_probe_is_read_with_its_p_bonferroni_over_both():
    """M = I on four rows, the residual r = (3, 3, 0, 0). The step's signature (per unit strength) points
    along (1, 0, 1, 0): cos^2 with r = 1/4, LM = (u.r)^2 = 4.5; the top's along (1, 1, 0, 0): cos^2 1, LM 18.
    The top is read: explained 1, LM 18, p = 2 x P(chi2_1 > 18) / 2; its strength from the top's secant:
    gamma = s.r / s.s with s = (0.01, 0.01, 0, 0) per J/m2 -> 6 / 0.0002 = 300 J/m2."""
    table = candidates()
    M = np.eye(4)
    r = np.array([3.0, 3.0, 0.0, 0.0])
    step = Signature(table["cohesion_adhesive"], np.array([0.01, 0.0, 0.01, 0.0]), 60.0)
    top = Signature(table["cohesion_adhesive"], np.array([0.01, 0.01, 0.0, 0.0]), 200.0, probe=TOP)
    loc = Localisation(stats.lack_of_fit(r, M, np.full(4, np.inf)), rows=[], tests=[], trends={}, conflicts={})
    att = attribute(loc, r, M, [step, top], ["a", "b", "c", "d"])
    (row,) = att.ranking
    assert row.probe == TOP
    assert row.score.lm == pytest.approx(18.0) and row.score.explained == pytest.approx(1.0)
    assert row.score.p_value == pytest.approx(2 * 0.5 * sps.chi2.sf(18.0, 1))
    assert row.strength == pytest.approx(300.0)
    by_probe = {d["probe"]: d for d in row.probes}
    assert by_probe[STEP]["lm"] == pytest.approx(4.5) and by_probe[STEP]["explained"] == pytest.approx(0.25)
    assert by_probe[STEP]["strength_probed"] == pytest.approx(60.0)
    assert by_probe[TOP]["strength_probed"] == pytest.approx(200.0)
    # the directed test takes the maximum over both probes' signatures: Bonferroni's 2 x P(chi2_1 > 18) / 2
    assert att.directed.p_value == pytest.approx(2 * 0.5 * sps.chi2.sf(18.0, 1))
    assert att.verdict == DiagnosisVerdict.INDICATED and "probed at 200" in att.message
    # one probe alone: its p as the score test gives it, no detail listed
    (alone,) = attribute(loc, r, M, [step], ["a", "b", "c", "d"]).ranking
    assert alone.score.p_value == pytest.approx(0.5 * sps.chi2.sf(4.5, 1)) and alone.probes == []
    assert math.isclose(alone.strength, 0.03 / 0.0002)  # s.r / s.s on the step's secant: 150 J/m2


def test_the_loop_probes_the_named_candidates_at_their_top_at_the_seeds_run(monkeypatch):
    """Plumbing: forced to find cohesion seen but not named, the diagnosis runs it at 200 J/m2 at the seeds its
    step's batteries ran at, after them, and ranks it on both probes."""
    calls = []

    def forced(diagnosis, probed=frozenset()):
        calls.append(set(probed))
        return [] if "cohesion_adhesive" in probed else ["cohesion_adhesive"]

    monkeypatch.setattr(attribute_mod, "top_probes", forced)
    case = make_case(7, "single", effects={"cohesion_adhesive": 150.0})
    settings = loop_settings(case, diagnose_always=True, automatic=False)
    result = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), settings).run()
    it = result.first
    plan = it.report["diagnosis_plan"]
    runs = sorted((r for r in it.runs if r.kind == RunKind.DIAGNOSIS), key=lambda r: r.std_order)
    assert len(plan) == len(runs) == it.report["diagnosis"]["batteries"]
    tops = [(p, r) for p, r in zip(plan, runs) if p.get("probe") == TOP]
    step_seeds = {p["seed"] for p in plan if p["effect"] == "baseline"}
    assert tops and {p["seed"] for p, _ in tops} == step_seeds
    assert all(p["effect"] == "cohesion_adhesive" for p, _ in tops)
    assert all(r.natural["effects.cohesion_adhesive.surface_energy_j_m2"] == pytest.approx(200.0) for _, r in tops)
    assert plan.index(tops[0][0]) > max(i for i, p in enumerate(plan) if p.get("probe") is None)
    stages = it.report["diagnosis_stages"]
    assert any(s.get("top_probes") == ["cohesion_adhesive"] for s in stages)
    row = next(r for r in it.report["diagnosis"]["ranking"] if r["effect"] == "cohesion_adhesive")
    assert {d["probe"] for d in row["probes"]} == {STEP, TOP}
    assert calls[-1] == {"cohesion_adhesive"}  # asked again after the top's batteries, with it marked probed
