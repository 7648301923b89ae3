"""The "liggghts" export format (service.export.formats) reads the material card alone, and LIGGGHTS reads
what it writes: the card's parameters reach the include unchanged in SI."""
import pytest
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


def test_a_card_at_a_material_resolution_states_its_sizes_and_reads_back():
    """Radii uniform in 19-21 mm in Appendix A's rig, as measured: the card's distribution is uniform with
    mean 20 mm and sd 2 mm / sqrt(12); the card validates, reads back to the same parameters, and becomes an
    include."""
    from engine.lab.rigs import bundled_rig, rig_json
    from service.export.card import CARD_FORMAT, CARD_VERSION, canonical, micro_parameters, physics_sections, validate

    particles = {"shapes": [{"shape": "sphere", "volume_fraction": 1.0,
                             "size": {"form": "uniform", "radius_min_m": 0.019, "radius_max_m": 0.021}}]}
    where = {"fidelity": None, "resolution": "as_measured", "scale_factor": 1.0, "test": "battery", "options": {},
             "rig_record": rig_json(bundled_rig("appendix-a-400mm-shear-box")), "material_particles": particles}
    params = MicroParameters(friction_pp=0.45)
    card = canonical({"card_version": CARD_VERSION, "format": CARD_FORMAT, "demcal_version": "test",
                      "material": {"name": "spread"}, **physics_sections(params, where), "calibration": None})
    distribution = card["particles"]["shapes"][0]["radius_distribution"]
    assert distribution["kind"] == "uniform" and distribution["mean_m"] == pytest.approx(0.020, rel=1e-12)
    assert distribution["sd_m"] == pytest.approx(0.002 / 12 ** 0.5, rel=1e-12)
    assert card["rig"]["container_radius_m"] == 0.2 and card["rig"]["resolution"] == "as_measured"
    assert micro_parameters(validate(card)) == params
    assert "0.45" in get("liggghts").render(card)
