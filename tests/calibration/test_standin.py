"""The closed-form stand-in knows exactly the engine's effects, and each effect moves the bulk
quantities the way its module's fingerprint (the physics it declares) says."""
import math

import pytest

from calibration import parameters, standin
from engine.candidates import candidates
from engine.lab.spec import MicroParameters

COND = standin.Conditions(cct_window_stresses_pa=(15e3, 60e3), include_aor=True, include_anchor=True)
BASE = {"particle_density_kg_m3": 2600.0, "friction_pp": 0.6, "friction_pw": 0.5,
        "particle_stiffness_n_per_m": 1.7e6}


def _columns(params):
    # noise-free battery, then the lab's derived quantities (Mohr-Coulomb fit, mean dilatancy)
    recs = standin.battery(params, 0, COND, noise_scale=0.0)
    get = lambda q, **c: next(r["value"] for r in recs if r["quantity"] == q and r["condition"] == c)  # noqa: E731
    return {"bulk_density": get("bulk_density_kg_m3"), "modulus_level": get("confined_modulus_pa"),
            "modulus_slope": math.log(get("confined_modulus_pa", normal_stress_pa=60e3)
                                      / get("confined_modulus_pa", normal_stress_pa=15e3)),
            "cohesion": get("cohesion_pa"), "friction_angle": get("friction_angle_deg"),
            "dilatancy": get("dilatancy_angle_deg"), "angle_of_repose": get("angle_of_repose_deg"),
            "pull_force": get("peak_pull_force_n")}


@pytest.mark.parametrize("name", sorted(candidates()))
def test_each_effect_moves_the_quantities_its_fingerprint_declares(name):
    c = candidates()[name]
    strength = (c.reference(MicroParameters.model_validate(BASE)) if c.is_switch
                else c.plausible_range[1])
    off, on = _columns(BASE), _columns(parameters.apply(BASE, {c.factor: strength}))
    for column, sign in c.fingerprint.items():
        if sign in ("+", "++"):
            assert on[column] > off[column], (name, column)
        elif sign == "-":
            assert on[column] < off[column], (name, column)


def test_the_hertz_switch_keeps_the_modulus_at_the_match_stress_and_steepens_it():
    # calibration/standin's E' is written about 30 kPa, where the candidate's matched modulus gives the
    # linear contact's stiffness: the level there is unchanged, the log-log slope becomes the Hertz exponent
    cond = standin.Conditions(cct_window_stresses_pa=(30e3,))
    c = candidates()["hertz_mindlin"]
    on = parameters.apply(BASE, {c.factor: c.reference(MicroParameters.model_validate(BASE))})
    level = lambda p: next(r["value"] for r in standin.bulk_values(p, cond) if r["condition"])  # noqa: E731
    assert level(on) == pytest.approx(level(BASE), rel=1e-9)


def test_unknown_effects_and_parameters_are_refused_as_the_engine_refuses_them():
    with pytest.raises(ValueError, match="unknown contact effect 'rolling_resistance'"):
        standin.bulk_values({"effects": {"rolling_resistance": {"rolling_friction": 0.2}}}, COND)
    with pytest.raises(ValueError, match="rolling_friction"):
        standin.bulk_values({"effects": {"rolling_epsd2": {"rolling_friction": "abc"}}}, COND)
    # the constant-torque model is rolling resistance too: it is not silently ignored
    plain = _columns(BASE)["friction_angle"]
    cdt = _columns(parameters.apply(BASE, {"effects.rolling_constant_torque.rolling_friction": 0.2}))
    assert cdt["friction_angle"] > plain + 5.0


def test_factor_names_are_checked_against_the_registry():
    assert parameters.check_factor("effects.rolling_epsd2.rolling_friction")
    with pytest.raises(ValueError, match="unknown effect 'rolling_resistance'"):
        parameters.check_factor("effects.rolling_resistance.rolling_friction")
    with pytest.raises(ValueError, match="has no parameter 'mu_r'"):
        parameters.check_factor("effects.rolling_epsd2.mu_r")


def test_a_perturbed_world_is_another_world():
    import numpy as np

    other = standin.Gains().perturbed(np.random.default_rng(0))
    a = standin.bulk_values(BASE, COND)
    b = standin.bulk_values(BASE, COND, other)
    assert all(x["value"] != y["value"] for x, y in zip(a, b) if x["quantity"] != "voids_ratio")
