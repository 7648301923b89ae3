"""The "liggghts" export format (service.export.formats) reads the material card alone, and LIGGGHTS reads
what it writes: the card's parameters reach the include unchanged in SI."""
from liggghts_support import require_liggghts

from engine.lab.spec import MicroParameters
from service.export.card import parameters_card
from service.export.formats import get


def _card():
    params = MicroParameters.model_validate({"friction_pp": 0.45, "particle_stiffness_n_per_m": 2.0e6,
                                             "effects": {"rolling_epsd2": {"rolling_friction": 0.2}}})
    return parameters_card(params, fidelity="screening")


def test_the_card_becomes_an_include_with_its_parameters():
    text = get("liggghts").render(_card())
    # PFC springs in series: two equal particles of 2e6 N/m touch with 1e6 N/m
    assert "kp kp/(kp+kp) = 1000000 N/m" in text
    assert "0.45" in text and "epsd2" in text


def test_liggghts_accepts_the_cards_include():
    require_liggghts()
    from calibration.export.liggghts import render
    from calibration.export.material import from_micro_parameters
    from calibration.export.rig_liggghts import check_syntax
    from service.export.card import micro_parameters, validate

    model = validate(_card())
    assert "SYNTAX_OK" in check_syntax(render(from_micro_parameters(micro_parameters(model), model.rig.fidelity)))
