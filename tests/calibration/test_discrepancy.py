"""Model-form discrepancy (calibration.discrepancy): sizes, Satterthwaite's degrees of freedom and the
estimate from two models' runs, each against a hand calculation; and the noise model it enters."""
import math

import pytest
from pydantic import ValidationError

from calibration.calibrate import target_variances
from calibration.discrepancy import Discrepancy, combined, discrepancy_term, from_comparison
from calibration.keys import ResponseKey
from calibration.records import Measured, VarianceTerm

E_20K = ResponseKey.of("cct", "confined_modulus_pa", {"normal_stress_pa": 20e3})
E_60K = ResponseKey.of("cct", "confined_modulus_pa", {"normal_stress_pa": 60e3})
DIL = ResponseKey.of("dst", "dilatancy_angle_deg", {"normal_stress_pa": 24e3})


def test_term_relative_and_absolute():
    d = Discrepancy(test="cct", relative_sd=0.1, absolute_sd=2.0e3)
    # (0.1 x 200 kPa)^2 + (2 kPa)^2 = 4.0e8 + 4.0e6 Pa^2
    assert d.term(200e3).variance == pytest.approx(4.04e8)
    assert math.isinf(d.term(200e3).df)


def test_the_quantitys_entry_wins_over_the_tests():
    entries = [Discrepancy(test="cct", relative_sd=0.2), Discrepancy(test="cct", quantity="confined_modulus_pa",
                                                                     relative_sd=0.05)]
    assert discrepancy_term(E_20K, 100.0, entries).variance == pytest.approx(25.0)
    assert discrepancy_term(DIL, 5.0, entries) is None


def test_satterthwaite_degrees_of_freedom():
    # v = 1 (2 df) + 3 (exact): total 4, df = 4^2 / (1^2 / 2) = 32
    out = combined(VarianceTerm(1.0, 2.0, "replicates"), VarianceTerm(3.0, math.inf, "model-form discrepancy"))
    assert out.variance == pytest.approx(4.0) and out.df == pytest.approx(32.0)
    # both estimated: v = 1 (2 df) + 1 (4 df): df = 4 / (1/2 + 1/4) = 5.333
    out = combined(VarianceTerm(1.0, 2.0, "a"), VarianceTerm(1.0, 4.0, "b"))
    assert out.df == pytest.approx(16.0 / 3.0)


def test_from_comparison_by_hand():
    ours = {E_20K: 100e6, E_60K: 200e6, DIL: 30.0}
    theirs = {E_20K: 110e6, E_60K: 180e6, DIL: 32.0}
    got = {(d.test, d.quantity): d for d in from_comparison(ours, theirs)}
    # E': -10/105 and +20/190 relative to the pair's mean; rms over the two conditions, 2 df
    rms = math.sqrt(((10 / 105) ** 2 + (20 / 190) ** 2) / 2)
    e = got[("cct", "confined_modulus_pa")]
    assert e.relative_sd == pytest.approx(rms) and e.absolute_sd == 0.0 and e.df == 2.0
    # angles absolute: 2 degrees on 1 df
    dil = got[("dst", "dilatancy_angle_deg")]
    assert dil.absolute_sd == pytest.approx(2.0) and dil.relative_sd == 0.0 and dil.df == 1.0


def test_variances_carry_the_discrepancy():
    # E' measured 100 MPa with a stated 5 MPa: 25e12 + (0.12 x 100 MPa)^2 = 25e12 + 144e12 Pa^2
    m = Measured(E_20K, (100e6,), "Pa", stated_uncertainty=5e6)
    plain = target_variances([m], 0.05)[E_20K]
    given = target_variances([m], 0.05, [Discrepancy(test="cct", relative_sd=0.12)])[E_20K]
    assert plain.variance == pytest.approx(25e12)
    assert given.variance == pytest.approx(169e12)
    assert "model-form discrepancy" in given.source


@pytest.mark.parametrize("bad, field", [
    ({"test": "shear", "relative_sd": 0.1}, "test"),
    ({"test": "cct", "quantity": "bulk_density_kg_m3", "relative_sd": 0.1}, "quantity"),
    ({"test": "cct"}, "relative_sd"),
    ({"test": "cct", "relative_sd": -0.1}, "relative_sd"),
    ({"test": "cct", "relative_sd": True}, "relative_sd"),
])
def test_bad_entries_are_refused(bad, field):
    with pytest.raises(ValidationError) as err:
        Discrepancy.model_validate(bad)
    assert field in str(err.value)
