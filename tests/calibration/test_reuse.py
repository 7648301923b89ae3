"""Issue 34, item 1: an iteration reuses the batteries earlier iterations ran at points of its own model.

The numbers here are the designs' own arithmetic: a 2^(4-1) design crossed with one more two-level factor
is a 2^(5-1) of 16 factorial points whose low face is the 2^(4-1); three centre replicates bring two
pure-error degrees of freedom; a battery of a model with another effect switched on is a point of no
model without it.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from calibration import reuse
from calibration.adding import with_effect_factor
from calibration.design import build_design
from calibration.settings import DesignIn, FactorIn
from doe.fit import default_terms
from doe.terms import model_matrix

FOUR = [FactorIn(name="particle_density_kg_m3", low=2300.0, high=2900.0),
        FactorIn(name="friction_pp", low=0.2, high=1.0),
        FactorIn(name="friction_pw", low=0.2, high=0.8),
        FactorIn(name="particle_stiffness_n_per_m", low=1.0e6, high=3.0e6)]
ROLLING = "effects.rolling_epsd2.rolling_friction"


def _iteration(number, factors, design_settings, seed, fixed=None, extra_runs=()):
    """An evaluated iteration as the machine stores it: its design's runs with (fake) responses."""
    design = build_design(factors, design_settings, seed)
    runs = []
    for i, row in enumerate(design.records("std")):
        natural = {f.name: row[f.name] for f in factors}
        runs.append(SimpleNamespace(kind="design", std_order=i + 1, seed=int(row["seed"]), natural=natural,
                                    responses={"r": {"value": float(i)}}, job_id=100 + i, reused_from=None))
    runs += list(extra_runs)
    parameters = {"factors": [f.model_dump() for f in factors], "fixed": dict(fixed or {}), "effects": {}}
    return SimpleNamespace(number=number, parameters=parameters, runs=runs), design


def test_a_battery_without_the_effect_is_the_new_model_at_strength_zero():
    point = {"particle_density_kg_m3": 2600.0, "friction_pp": 0.5, "friction_pw": 0.4,
             "particle_stiffness_n_per_m": 2e6}
    five = FOUR + [FactorIn(name=ROLLING, low=0.0, high=0.3)]
    at = reuse.coordinates(point, {}, five)
    assert at is not None and at[ROLLING] == 0.0 and at["friction_pp"] == 0.5
    # the same model spelled with the effect present at its vanishing strength is the same point
    zero = {**point, "effects": {"rolling_epsd2": {"rolling_friction": 0.0}}}
    assert reuse.canonical(zero) == reuse.canonical(point)
    # rolling resistance switched on is no point of the model without it, nor another fixed parameter
    on = {**point, "effects": {"rolling_epsd2": {"rolling_friction": 0.1}}}
    assert reuse.coordinates(on, {}, FOUR) is None
    assert reuse.coordinates(point, {"particle_radius_m": 0.035}, FOUR) is None


def test_the_added_effect_s_low_face_is_the_previous_design():
    first_settings = DesignIn(type="fractional", generators=["D=ABC"], centre_runs=3)
    first, first_design = _iteration(1, FOUR, first_settings, seed=5)
    config = {"factors": [f.model_dump() for f in FOUR], "design": first_settings.model_dump(),
              "fixed_parameters": {}}
    nxt = with_effect_factor(config, "rolling_epsd2", strength_range=(0.0, 0.3))
    assert nxt["design"]["generators"] == ["D=ABC"]  # crossed, not the 2^(5-1) V whose faces are other fractions
    five = [FactorIn.model_validate(f) for f in nxt["factors"]]
    design = build_design(five, DesignIn.model_validate(nxt["design"]), seed=6)
    assert design.n_runs == 16 + 3
    earlier = reuse.earlier_runs([first], 2, {}, five)
    assert len(earlier) == 11 and all(e.natural[ROLLING] == 0.0 for e in earlier)
    merged = reuse.with_earlier(design, earlier)
    d = merged.design
    new = [i for i, s in enumerate(merged.sources) if s is None]
    # 8 factorial points at the high face and one centre of the new box are run; the 8 low-face points
    # are the first design's; its 3 centre runs (the low face's centre) are further points of the fit
    assert len(new) == 9
    assert sorted(d.point_type[i] for i in new) == ["center"] + ["factorial"] * 8
    assert all(d.coded[i, 4] == 1.0 for i in new if d.point_type[i] == "factorial")
    reused_points = [i for i, s in enumerate(merged.sources) if s is not None and d.point_type[i] == "factorial"]
    assert len(reused_points) == 8 and all(d.coded[i, 4] == -1.0 for i in reused_points)
    assert [d.point_type[i] for i, s in enumerate(merged.sources) if s is not None and s.kind == "design"
            and d.point_type[i] != "factorial"] == ["other"] * 3
    # a reused row keeps its battery's seed; no new run shares a seed with a reused one
    assert all(int(d.seed[i]) == s.seed for i, s in enumerate(merged.sources) if s is not None)
    assert len(set(d.seed.tolist())) == d.n_runs
    # the merged design is a 2^(5-1) with I = ABCD: E and its interactions clear, AB = CD as before
    assert d.aliases.resolution == 4
    X = model_matrix(d.coded, default_terms(d))
    assert np.linalg.matrix_rank(X) == X.shape[1]
    # pure error: 3 old centre replicates (2 df); the new centre is alone
    from doe.fit import pure_error
    assert pure_error(d.coded, np.arange(d.n_runs, dtype=float))[1] == 2
    # the runs to do come first in run order
    assert sorted(int(d.run_order[i]) for i in new) == list(range(1, 10))


def test_a_switch_effect_has_no_off_face_and_reuses_nothing():
    first, _ = _iteration(1, FOUR, DesignIn(type="fractional", generators=["D=ABC"], centre_runs=3), seed=5)
    hertz = {"effects": {"hertz_mindlin": {"young_modulus_pa": 5e7, "poisson_ratio": 0.25}}}
    from engine.lab.spec import MicroParameters
    MicroParameters.model_validate(hertz)  # a valid model, so nothing is refused for being malformed
    assert reuse.earlier_runs([first], 2, hertz, FOUR) == []
    assert len(reuse.earlier_runs([first], 2, {}, FOUR)) == 11


@pytest.mark.parametrize("centre_runs, brought, expected", [(3, 2, 1), (3, 0, 3), (5, 2, 3), (0, 2, 0)])
def test_centre_runs_run_only_the_pure_error_the_reused_replicates_do_not_bring(centre_runs, brought, expected):
    """c centre runs give c - 1 pure-error df; reused replicates bring some; at least one centre is run."""
    design = build_design(FOUR, DesignIn(type="fractional", generators=["D=ABC"], centre_runs=centre_runs), seed=1)
    far = (0.5, 0.5, 0.5, 0.5)  # replicates off the design's points
    earlier = [reuse.Earlier(1, "confirmation", k, 900 + k, {}, far, {}, None) for k in range(brought + 1)]
    merged = reuse.with_earlier(design, earlier)
    centres = [i for i, s in enumerate(merged.sources) if s is None and merged.design.point_type[i] == "center"]
    assert len(centres) == expected


def test_batteries_of_another_set_up_are_never_reused():
    """Other loads (battery options), another resolution or another evaluator: the earlier batteries measured
    something else, so an iteration that changes its set-up starts from its own batteries."""
    from calibration.machine import iteration_parameters
    from calibration.settings import LoopSettings

    base = {"factors": [f.model_dump() for f in FOUR], "design": {"type": "fractional", "generators": ["D=ABC"]}}
    settings = LoopSettings.model_validate(base)
    first, _ = _iteration(1, FOUR, settings.design, seed=5)
    first.parameters = iteration_parameters(settings, "dem")
    assert len(reuse.earlier_runs([first], 2, {}, FOUR, iteration_parameters(settings, "dem"))) == 11
    for changed, evaluator in [({"options": {"dst_normal_stresses_pa": [20e3, 40e3]}}, "dem"),
                               ({"resolution": "thesis"}, "dem"), ({}, "analytic")]:
        other = iteration_parameters(LoopSettings.model_validate({**base, **changed}), evaluator)
        assert reuse.earlier_runs([first], 2, {}, FOUR, other) == [], changed or evaluator
    # an iteration stored before the key existed: its options, preset and evaluator are compared
    old = {k: v for k, v in first.parameters.items() if k != "setup_key"}
    assert reuse.same_setup(old, iteration_parameters(settings, "dem"))
    assert not reuse.same_setup(old, iteration_parameters(LoopSettings.model_validate(
        {**base, "options": {"cct_cycles": 2}}), "dem"))
