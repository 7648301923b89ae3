"""An effect whose law replaces a baseline one takes the replaced parameters out of the calibration
(``Candidate.supersedes``, ``calibration.adding.without_superseded``): Hertz-Mindlin's force reads E* and G*
only, so with it on the linear spring's kp is fixed where the effect was added, not calibrated on scatter."""
from __future__ import annotations

import math

import numpy as np
import pytest

from calibration.adding import with_effect_factor
from calibration.settings import LoopSettings
from engine.candidates import candidates
from engine.effects import hertz_mindlin
from engine.effects.base import Candidate

FACTORS = [{"name": "particle_density_kg_m3", "low": 2300.0, "high": 2900.0},
           {"name": "friction_pp", "low": 0.2, "high": 1.0},
           {"name": "friction_pw", "low": 0.2, "high": 0.8},
           {"name": "particle_stiffness_n_per_m", "low": 1.0e6, "high": 3.0e6}]
# kp off its box's centre (2e6), as at tier B hertz_strong's iteration 1 optimum: "fixed at the optimum" and
# "matched at the optimum" must not pass by the centre's coincidence
OPTIMUM = {"particle_density_kg_m3": 2650.0, "friction_pp": 0.6, "friction_pw": 0.5,
           "particle_stiffness_n_per_m": 1.6e6}
MODULUS = "effects.hertz_mindlin.young_modulus_pa"


def test_the_hertzian_force_does_not_read_the_linear_spring():
    """Hertz: F = 4/3 E* sqrt(R* d) d, tangent 2 E* sqrt(R* d), ks = 8 G* sqrt(R* d), whatever kn and ks the
    linear law would have given (R* 10 mm, d 0.1 mm, E* 1 GPa, G* 0.4 GPa)."""
    p = np.array([0.0, 1.0e9, 0.4e9])
    r_eff, delta = 0.010, 1.0e-4
    root = math.sqrt(r_eff * delta)
    expected = (4.0 / 3.0 * 1.0e9 * root * delta, 2.0e9 * root, 8.0 * 0.4e9 * root)
    for kn, ks in ((1.0e6, 1.0e6), (3.0e6, 0.5e6), (0.0, 0.0)):
        assert hertz_mindlin.apply(p, delta, r_eff, kn, ks) == pytest.approx(expected, rel=1e-12)
    assert candidates()["hertz_mindlin"].supersedes == ("particle_stiffness_n_per_m",)


def test_adding_hertz_fixes_kp_at_the_optimum_and_the_design_shrinks_to_four_factors():
    config = {"factors": [dict(f) for f in FACTORS], "design": {"type": "fractional", "generators": ["D=ABC"]},
              "fixed_parameters": {"particle_radius_m": 0.02},
              "priors": [{"parameter": "particle_stiffness_n_per_m", "value": 2.1e6, "uncertainty": 0.2e6},
                         {"parameter": "friction_pp", "value": 0.65, "uncertainty": 0.08}],
              "constraints": ["friction_pw <= friction_pp", "particle_stiffness_n_per_m >= 1.5e6"]}
    nxt = with_effect_factor(config, "hertz_mindlin", at=OPTIMUM)
    assert [f["name"] for f in nxt["factors"]] == ["particle_density_kg_m3", "friction_pp", "friction_pw", MODULUS]
    assert nxt["fixed_parameters"] == {"particle_radius_m": 0.02, "particle_stiffness_n_per_m": 1.6e6}
    assert [p["parameter"] for p in nxt["priors"]] == ["friction_pp"]
    assert nxt["constraints"] == ["friction_pw <= friction_pp"]
    assert nxt["design"]["generators"] == ["D=ABC"]  # four factors again: the 2^(4-1) IV
    # the modulus range is about the one matched to kp = 1.6e6 N/m at the optimum (matched_young_modulus_pa:
    # E ~ kp^1.5, so the centre's 2e6 would put it 1.4x higher)
    low, high = next((f["low"], f["high"]) for f in nxt["factors"] if f["name"] == MODULUS)
    from engine.lab.spec import MicroParameters

    matched = hertz_mindlin.matched_young_modulus_pa(MicroParameters.model_validate({**OPTIMUM, "particle_radius_m": 0.02}))
    assert low < matched < high and math.isclose(math.sqrt(low * high), matched, rel_tol=1e-9)
    LoopSettings.model_validate(nxt)  # the loop's own validation accepts it (no prior on a non-factor)
    assert config["factors"][3]["name"] == "particle_stiffness_n_per_m"  # the caller's configuration untouched


def test_without_an_optimum_kp_is_fixed_at_its_range_centre_and_other_effects_keep_it():
    config = {"factors": [dict(f) for f in FACTORS], "design": {}, "fixed_parameters": {}}
    nxt = with_effect_factor(config, "hertz_mindlin", strength_range=(5.0e8, 5.0e9))
    assert nxt["fixed_parameters"]["particle_stiffness_n_per_m"] == 2.0e6
    rolling = with_effect_factor(config, "rolling_epsd2", strength_range=(0.0, 0.3))
    assert "particle_stiffness_n_per_m" in [f["name"] for f in rolling["factors"]]


def test_only_a_law_that_replaces_the_baseline_may_supersede_its_parameters():
    with pytest.raises(ValueError, match="supersedes"):
        Candidate(name="x", title="x", factor="effects.x.k", unit="1", plausible_range=(0.0, 1.0), step=0.1,
                  supersedes=("particle_stiffness_n_per_m",))


def test_a_pinned_stiffness_the_added_law_supersedes_is_fixed_not_widened():
    """The stand-in's Hertz world (tier A seed 13: E 1.09 GPa, kp 1.74 MN/m) with the stiffness box drawn below
    its kp (top at 0.75 x). Iteration 1 pins kp at that top and the diagnosis names Hertz-Mindlin. The box
    rule alone would widen kp for the next iteration; Hertz's force reads no kp, so the record says no
    widening, kp is fixed where it was pinned, and the next iteration calibrates E over a range holding the
    truth (E ~ kp^1.5: the range is centred 0.65 x the modulus matched to the true kp, which it still holds)."""
    from calibration.automatic import box_widening
    from calibration.conditions import standin_conditions
    from calibration.evaluators import StandinEvaluator
    from calibration.loop import CalibrationLoop
    from calibration.testbed import FACTORS as TIER_A_FACTORS
    from calibration.testbed import OPTIONS, loop_settings, make_case

    stiffness = "particle_stiffness_n_per_m"
    case = make_case(13, "single")
    truth_kp, truth_e = case.truth[stiffness], case.truth["effects"]["hertz_mindlin"]["young_modulus_pa"]
    factors = [dict(f, low=0.5e6, high=0.75 * truth_kp) if f["name"] == stiffness else dict(f) for f in TIER_A_FACTORS]
    settings = loop_settings(case, 3, factors=factors)
    result = CalibrationLoop(case.targets, StandinEvaluator(standin_conditions(OPTIONS)), settings).run()
    first, second = result.iterations[:2]
    pinned = {b["parameter"]: b["side"] for b in first.report["conflicts"]["active_bounds"]}
    assert pinned == {stiffness: "high"} and first.report["diagnosis"]["indicated"][0] == "hertz_mindlin"
    # what the box rule alone would record for kp, before the guard drops it
    _, box = box_widening(result.iterations[:1], first, first.report, settings.priors)
    assert [w["parameter"] for w in box] == [stiffness]
    record = first.report["automatic"]
    assert record["next_effect"] == "hertz_mindlin" and "widened_box" not in record
    assert second.parameters["fixed"] == {stiffness: pytest.approx(0.75 * truth_kp)}
    assert stiffness not in [f["name"] for f in second.parameters["factors"]]
    low, high = next((f["low"], f["high"]) for f in second.parameters["factors"] if f["name"] == MODULUS)
    assert low < truth_e < high
    assert result.history()["iterations"][1]["box_widened"] == []
    assert second.report["verdict"] == "calibrated"
