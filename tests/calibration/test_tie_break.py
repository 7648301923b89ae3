"""Automatic mode between candidates the diagnosis cannot tell apart (calibration.automatic.cheapest_of_equals).

With one residual degree of freedom (four targets, three free parameters: the founding case once its fill
counts once) every candidate's signature is parallel to the misfit and the score test gives the same statistic
to all that move it the right way; which one led was decided by the last binary digit. Between equals the
cheaper battery is tried first: an elongated grain at equal volume is two spheres (engine/lab/shape.py), so a
shape battery has twice the spheres of a rolling-resistance one on the same packing."""
from __future__ import annotations

import pytest

from calibration.automatic import cheapest_of_equals

CONFIG = {"fidelity": "screening", "factors": [{"name": "particle_density_kg_m3", "low": 2300.0, "high": 2700.0},
                                               {"name": "friction_pp", "low": 0.3, "high": 1.0}]}
# the founding case's iteration 1 (27 Nov 2026): two scores equal to 1e-15, the others nothing
TIED = {"ranking": [{"effect": "particle_shape", "lm": 34.673346594385826},
                    {"effect": "rolling_epsd2", "lm": 34.67334659438582},
                    {"effect": "hertz_mindlin", "lm": 0.0}]}


def test_equal_scores_are_tried_cheapest_first_and_the_record_says_why():
    options, tie = cheapest_of_equals(["particle_shape", "rolling_epsd2", "hertz_mindlin"], TIED, CONFIG, {})
    assert options == ["rolling_epsd2", "particle_shape", "hertz_mindlin"]
    assert tie["equal"] == ["particle_shape", "rolling_epsd2"] and tie["chosen"] == "rolling_epsd2"
    # two spheres per elongated grain of the same volume: twice the spheres, to the rounding of the count
    assert tie["spheres"]["particle_shape"] / tie["spheres"]["rolling_epsd2"] == pytest.approx(2.0, rel=0.01)
    assert "cannot tell them apart" in tie["message"] and "fewest spheres" in tie["message"]


def test_a_score_the_data_prefer_keeps_its_place():
    ranked = {"ranking": [{"effect": "particle_shape", "lm": 34.7}, {"effect": "rolling_epsd2", "lm": 30.1}]}
    assert cheapest_of_equals(["particle_shape", "rolling_epsd2"], ranked, CONFIG, {}) == \
        (["particle_shape", "rolling_epsd2"], None)
    assert cheapest_of_equals(["particle_shape"], TIED, CONFIG, {}) == (["particle_shape"], None)


def test_the_history_carries_the_tie_break_to_the_page_and_the_api():
    from calibration.history import history
    from calibration.state import IterationState

    options, tie = cheapest_of_equals(["particle_shape", "rolling_epsd2"], TIED, CONFIG, {})
    its = [IterationState(number=1, parameters={"factors": []},
                          report={"automatic": {"next_effect": options[0], "tie_break": tie}}),
           IterationState(number=2, parameters={"factors": []}, report={"verdict": "calibrated"})]
    rows = history(its)["iterations"]
    assert rows[0]["tie_break"] == tie["message"] and rows[1]["tie_break"] is None
