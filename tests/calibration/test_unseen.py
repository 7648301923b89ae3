"""Which candidates a "no misfit" could not have seen (calibration.unseen): the power figure against the normal
distribution's, its rate measured on a fixed seed, and the cases worked by hand on signatures of known length."""
import dataclasses
import math

import numpy as np
import pytest

from calibration import stats
from calibration.attribute import Signature, attribute
from calibration.localise import Localisation
from calibration.unseen import DETECTION_POWER, critical_lm, detectable_lm, undetermined, unseen
from calibration.vocabulary import DiagnosisVerdict
from engine.candidates import candidates
from engine.lab.registry import units

ALPHA = 0.05
N_ROWS = 6


def _vector(first: float) -> np.ndarray:
    v = np.zeros(N_ROWS)
    v[0] = first
    return v


def test_the_noncentrality_needed_is_the_one_sided_z_tests():
    # one candidate: Holm's first step is the one-sided 5 % test, z 1.6449; 80 % power adds z 0.8416
    assert detectable_lm(ALPHA, 1) == pytest.approx((1.644854 + 0.841621) ** 2, rel=1e-6)  # 6.18
    # four candidates: the step is at alpha / 4 one-sided, z 2.2414
    assert math.sqrt(critical_lm(ALPHA, 4)) == pytest.approx(2.241403, rel=1e-6)
    assert detectable_lm(ALPHA, 4) == pytest.approx((2.241403 + 0.841621) ** 2, rel=1e-6)


def test_at_the_noncentrality_needed_the_score_test_flags_the_effect_at_the_stated_power():
    """Residuals r = sqrt(lambda) u + z with z standard normal (M = I, u a unit signature), at lambda =
    detectable_lm for four candidates: the one-sided score test clears Holm's first step in 80 % of draws."""
    rng = np.random.default_rng(20261129)
    need, crit = detectable_lm(ALPHA, 4), critical_lm(ALPHA, 4)
    u = _vector(1.0)
    M = np.eye(N_ROWS)
    draws = 20_000
    r = math.sqrt(need) * u + rng.standard_normal((draws, N_ROWS))
    flagged = np.mean([stats.score_test(row, u, M).lm > crit for row in r])
    print(f"score test at lambda {need:.2f}: flagged in {flagged:.4f} of {draws} draws (stated {DETECTION_POWER})")
    assert flagged == pytest.approx(DETECTION_POWER, abs=4 * math.sqrt(0.8 * 0.2 / draws))


def test_a_signature_too_short_at_its_plausible_top_is_unseen_and_its_revealing_measurement_named():
    table = candidates()
    M = np.eye(N_ROWS)
    # Hertz-Mindlin, a switch: its full switch moves the first row by 0.5 sd, LM 0.25 at the top
    hertz = Signature(table["hertz_mindlin"], _vector(0.5), 1.0, reference=1.1e9)
    # rolling resistance: 10 sd per unit friction, its plausible top 0.5 -> 5 sd, LM 25
    rolling = Signature(table["rolling_epsd2"], _vector(10.0), 0.15)
    need = detectable_lm(ALPHA, 2)
    rows = unseen([hertz, rolling], M, ALPHA, {"cct confined_modulus_pa @ normal_stress_pa=15000"})
    assert [row["effect"] for row in rows] == ["hertz_mindlin"]
    row = rows[0]
    assert row["lm_at_top"] == pytest.approx(0.25) and row["lm_needed"] == pytest.approx(need)
    assert row["smallest_seen"] == pytest.approx(math.sqrt(need) / 0.5)  # the fraction of the switch
    assert row["measure"] == ["cct unload_reload_modulus_pa at several normal stresses, e.g. 3-60 kPa "
                              "(options.cct_unload_reload_stresses_pa)"]
    # already measured: more replicates of it
    again = unseen([hertz], M, ALPHA, {"cct unload_reload_modulus_pa @ normal_stress_pa=3000"})[0]
    assert again["measure"][0].startswith("more replicates of cct unload_reload_modulus_pa")


def test_an_additive_effects_smallest_seen_strength_and_the_probes_noise():
    table = candidates()
    M = np.eye(N_ROWS)
    # cohesion: 0.01 sd per J/m2 on one row; its top 200 J/m2 -> LM 4 below 6.18 (one candidate): unseen,
    # seen from sqrt(6.18) / 0.01 = 249 J/m2
    cohesion = Signature(table["cohesion_adhesive"], _vector(0.01), 60.0)
    row = unseen([cohesion], M, ALPHA, set())[0]
    assert row["lm_at_top"] == pytest.approx(4.0)
    assert row["smallest_seen"] == pytest.approx(math.sqrt(detectable_lm(ALPHA, 1)) / 0.01)
    # the same probe with noise of variance 1e-4 on the row (as large as its signal): the true signature may be
    # 0.01 + 1.96 x 0.01 long, LM (0.0296 x 200)^2 = 35 at the top, so "unseen" cannot be claimed
    noisy = dataclasses.replace(cohesion, noise_var=_vector(1.0e-4))
    assert unseen([noisy], M, ALPHA, set()) == []
    # a probe of nothing but small noise (variance 1e-10): unseen, on the bound (1.96e-5 x 200)^2 = 1.5e-5
    quiet = Signature(table["cohesion_adhesive"], np.zeros(N_ROWS), 60.0, noise_var=_vector(1.0e-10))
    assert unseen([quiet], M, ALPHA, set())[0]["lm_at_top"] == pytest.approx((1.96e-5 * 200.0) ** 2)


def test_no_misfit_names_what_it_could_not_see():
    """Residuals within the noise (all zero): "no misfit", and the message and "measure next" name the
    candidate the measurements could not have seen, not the one they could."""
    table = candidates()
    M = np.eye(N_ROWS)
    r = np.zeros(N_ROWS)
    df = np.full(N_ROWS, np.inf)
    loc = Localisation(stats.lack_of_fit(r, M, df), rows=[], tests=[], trends={}, conflicts={})
    signatures = [Signature(table["hertz_mindlin"], _vector(0.5), 1.0, reference=1.1e9),
                  Signature(table["rolling_epsd2"], _vector(10.0), 0.15)]
    labels = [f"dst residual_shear_stress_pa @ normal_stress_pa={s}" for s in range(N_ROWS)]
    att = attribute(loc, r, M, signatures, labels)
    assert att.verdict == DiagnosisVerdict.NO_MISFIT
    assert "could not see" in att.message and "hertz_mindlin" in att.message and "rolling_epsd2" not in att.message
    test, quantity, how = table["hertz_mindlin"].revealed_by[0]
    assert att.measure_next == [f"{test} {quantity} {how}"]
    assert [u["effect"] for u in att.to_dict()["unseen"]] == ["hertz_mindlin"]


def test_a_probe_too_noisy_to_tell_leaves_its_candidate_undetermined():
    """Cohesion at 0.01 sd per J/m2 on one row, its probe's noise sd 0.01 there: the true signature lies in
    0.01 -+ 1.96 x 0.01, i.e. 0 to 0.0296 long, so at the plausible top (200 J/m2) LM 0 to (0.0296 x 200)^2 =
    35.0 against the 6.18 needed (one candidate): neither seen nor unseen. Quiet, it is unseen (LM 4); ten times
    longer and quiet, it is seen (LM 400); neither of those is undetermined."""
    table = candidates()
    M = np.eye(N_ROWS)
    noisy = Signature(table["cohesion_adhesive"], _vector(0.01), 60.0, noise_var=_vector(1.0e-4))
    rows = undetermined([noisy], M, ALPHA, set())
    assert [row["effect"] for row in rows] == ["cohesion_adhesive"]
    assert rows[0]["lm_at_top_low"] == 0.0
    assert rows[0]["lm_at_top_high"] == pytest.approx((0.0296 * 200.0) ** 2, rel=1e-3)
    assert rows[0]["lm_needed"] == pytest.approx(detectable_lm(ALPHA, 1))
    quiet = dataclasses.replace(noisy, noise_var=None)
    assert undetermined([quiet], M, ALPHA, set()) == [] and unseen([quiet], M, ALPHA, set())
    seen = Signature(table["cohesion_adhesive"], _vector(0.1), 60.0, noise_var=_vector(1.0e-6))
    assert undetermined([seen], M, ALPHA, set()) == [] and unseen([seen], M, ALPHA, set()) == []


def test_no_misfit_does_not_rule_out_a_candidate_its_probe_could_not_judge():
    table = candidates()
    M = np.eye(N_ROWS)
    r = np.zeros(N_ROWS)
    loc = Localisation(stats.lack_of_fit(r, M, np.full(N_ROWS, np.inf)), rows=[], tests=[], trends={}, conflicts={})
    # Hertz's switch moves the first row 2 sd with probe noise of sd 2 there: LM 0 to (2 + 3.92)^2 = 35
    signatures = [Signature(table["hertz_mindlin"], _vector(2.0), 1.0, reference=1.1e9, noise_var=_vector(4.0)),
                  Signature(table["rolling_epsd2"], _vector(10.0), 0.15)]
    labels = [f"cct confined_modulus_pa @ normal_stress_pa={s}" for s in range(N_ROWS)]
    att = attribute(loc, r, M, signatures, labels)
    assert att.verdict == DiagnosisVerdict.NO_MISFIT and "does not rule it out" in att.message
    assert [u["effect"] for u in att.to_dict()["undetermined"]] == ["hertz_mindlin"] and att.unseen == []
    test, quantity, how = table["hertz_mindlin"].revealed_by[0]
    assert att.measure_next == [f"{test} {quantity} {how}"]


def test_every_revealing_measurement_is_one_the_lab_reports():
    known = units()
    for name, c in candidates().items():
        for test, quantity, _ in c.revealed_by:
            assert quantity in known.get(test, {}), (name, test, quantity)


def test_no_strength_is_read_for_an_unseen_candidate_or_against_the_effect():
    """The strength column (page, CLI, HTML report) reads ``calibration.attribute.strength_reading``. Cohesion
    at 0.01 sd per J/m2 with residual -242 sd on that row projects to -24,200 J/m2 (the page drew that): its
    signature is unseen, so no strength; a seen effect with a negative projection points against the effect;
    a switch gives its fraction; a significant candidate is read even if a noisier probe listed it unseen."""
    from calibration.attribute import strength_reading

    diagnosis = {"unseen": [{"effect": "cohesion_adhesive"}]}
    cohesion = {"effect": "cohesion_adhesive", "strength": -242.0 / 0.01, "fraction_of_switch": None,
                "significant": False}
    assert strength_reading(cohesion, diagnosis) == "unseen"
    assert strength_reading({**cohesion, "significant": True}, diagnosis) == "opposite sign"
    rolling = {"effect": "rolling_epsd2", "strength": 0.15, "fraction_of_switch": None, "significant": True}
    assert strength_reading(rolling, diagnosis) == 0.15
    assert strength_reading({**rolling, "strength": -0.05}, diagnosis) == "opposite sign"
    hertz = {"effect": "hertz_mindlin", "strength": None, "fraction_of_switch": 0.4, "significant": True}
    assert strength_reading(hertz, diagnosis) == 0.4
    assert strength_reading({**hertz, "fraction_of_switch": None}, diagnosis) is None
