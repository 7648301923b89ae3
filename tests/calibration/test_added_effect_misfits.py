"""Why an added effect's iteration is polished (``calibration.machine._added_effect_misfits``), and which missed
measured parameters the polish anchors on.

A prior the surfaces' optimum misses is passed to the polish (for its anchors, ``analysis.anchored_points``)
whatever else is wrong there: a failing lack of fit is what a biased surface's plateau leaves, and the anchors are
the way off it. Tier B's hertz_strong (session 42) had both at once, lack of fit p 0.013 and friction_pp 3.9 sd
above its tilt test, and before this rule its polish ran no anchor.
"""
from types import SimpleNamespace

import pytest

from calibration import analysis, machine

PULLED = [{"parameter": "friction_pp", "value": 0.655, "uncertainty": 0.08, "standardised_residual": 3.9,
           "meaning": "friction_pp calibrates 3.9 sd above its measured value"}]


def _iteration(**optimum):
    parameters = {"factors": [], "fixed": {}, "effects": {"hertz_mindlin": {"young_modulus_pa": 1.1e9}}}
    return SimpleNamespace(parameters=parameters, optimum={"parameters": {}, **optimum}, runs=[])


@pytest.fixture
def localised(monkeypatch):
    """The confirmation's localisation, set by each test: its lack of fit's p and the priors it finds missed."""
    made = {}

    def fake(config, design, modelled, optimum, records, seeds):
        return SimpleNamespace(lack_of_fit=SimpleNamespace(p_value=made["p"]),
                               conflicts={"priors_pulled": made["pulled"]})

    monkeypatch.setattr(analysis, "confirmation_localisation", fake)
    return made


@pytest.mark.parametrize("optimum, p, reason", [
    ({}, 0.013, "the confirmation's lack of fit fails (p 0.013)"),
    ({"active_bounds": [{"parameter": "friction_pp", "side": "high"}]}, 0.5, "a parameter pinned at a bound"),
    ({"reachability": [{"reachable": False}]}, 0.5, "a target out of the surfaces' reach"),
])
def test_a_missed_prior_is_named_and_anchored_beside_any_other_reason(localised, optimum, p, reason):
    localised.update(p=p, pulled=PULLED)
    why, pulled = machine._added_effect_misfits(SimpleNamespace(), _iteration(**optimum), None, [], [])
    assert why == f"{reason}; {PULLED[0]['meaning']}"
    assert pulled == PULLED


def test_a_missed_prior_alone_is_the_reason(localised):
    localised.update(p=0.5, pulled=PULLED)
    assert machine._added_effect_misfits(SimpleNamespace(), _iteration(), None, [], []) == (PULLED[0]["meaning"], PULLED)


def test_a_failing_fit_with_every_prior_met_polishes_without_anchors(localised):
    localised.update(p=0.013, pulled=[])
    assert machine._added_effect_misfits(SimpleNamespace(), _iteration(), None, [], []) == (
        "the confirmation's lack of fit fails (p 0.013)", [])


def test_a_passing_fit_that_meets_its_priors_is_not_polished_for_misfit(localised):
    localised.update(p=0.5, pulled=[])
    assert machine._added_effect_misfits(SimpleNamespace(), _iteration(), None, [], []) == (None, [])
