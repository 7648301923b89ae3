"""Each conversion of the LIGGGHTS export against a hand calculation written out here, and the include
itself accepted by LIGGGHTS-PUBLIC 3.8.0 (when installed; CI installs it).

Sources of the LIGGGHTS side: src/normal_model_hooke_stiffness.h (c = m* gamman with absolute_damping
off), src/normal_model_hertz.h (c = -2 sqrt(5/6) beta sqrt(Sn m*)), src/rolling_model_epsd2.h
(kr = kt reff^2), src/rolling_model_epsd.h (kr = 2.25 kn rmu^2 reff^2), src/pair_gran_base.h (m* of
rigid bodies is the body mass).
"""
from __future__ import annotations

import math
import re

import pytest

from calibration.export import conversions as cv
from calibration.export.liggghts import render
from calibration.export.material import ExportMaterial
from liggghts_support import require_liggghts

# One 20 mm sphere of 2500 kg/m3: m = 4/3 pi (0.02 m)^3 2500 kg/m3 = 3.3510e-5 m3 x 2500 = 0.083776 kg
SCREENING_SPHERE_MASS_KG = 0.0837758


def _material(**over) -> ExportMaterial:
    data = {
        "name": "test",
        "particles": {"solid_density_kg_m3": 2500.0, "spheres": [{"radius_m": 0.02, "volume_fraction": 1.0}]},
        "contact": {"particle_stiffness_n_per_m": 1.72e6, "wall_stiffness_n_per_m": 1.0e7,
                    "shear_to_normal_stiffness_ratio": 1.0, "damping_ratio_normal": 0.8,
                    "damping_ratio_shear": 0.8, "friction_pp": 0.5, "friction_pw": 0.3},
        "effects": {},
    }
    for key, value in over.items():
        if key in ("particles", "contact"):
            data[key].update(value)
        else:
            data[key] = value
    return ExportMaterial.model_validate(data)


def _pair_values(text: str, prop: str) -> list[float]:
    line = next(ln for ln in text.splitlines() if re.match(rf"fix \S+ all property/global {prop} ", ln))
    words = line.split()
    return [float(w) for w in words[words.index("peratomtypepair") + 2:]] if "peratomtypepair" in words else \
        [float(w) for w in words[words.index("peratomtype") + 1:]]


def test_series_stiffness_of_pfc_entities():
    # two particles of kp = 1.72 MN/m: 1.72e6 x 1.72e6 / 3.44e6 = 0.86 MN/m (half of kp)
    assert cv.series_stiffness_n_per_m(1.72e6, 1.72e6) == pytest.approx(0.86e6, rel=1e-12)
    # particle and wall kw = 10 MN/m: 1.72e6 x 1e7 / 1.172e7 = 1.4675768 MN/m
    assert cv.series_stiffness_n_per_m(1.72e6, 1.0e7) == pytest.approx(1.4675768e6, rel=1e-7)


def test_effective_mass_and_radius():
    # 10 mm and 15 mm spheres at 2500 kg/m3: m1 = 0.0104720 kg, m2 = 0.0353429 kg,
    # m* = m1 m2 / (m1 + m2) = 3.70110e-4 / 0.0458149 = 0.00807838 kg
    m1, m2 = cv.sphere_mass_kg(2500.0, 0.010), cv.sphere_mass_kg(2500.0, 0.015)
    assert m1 == pytest.approx(0.0104720, rel=1e-5)
    assert m2 == pytest.approx(0.0353429, rel=1e-5)
    assert cv.effective_mass_kg(m1, m2) == pytest.approx(0.00807838, rel=1e-5)
    assert cv.effective_mass_kg(m1) == m1  # a wall is infinitely heavy
    # R* = 10 x 15 / 25 = 6 mm; a wall: the particle's radius
    assert cv.effective_radius_m(0.010, 0.015) == pytest.approx(0.006, rel=1e-12)
    assert cv.effective_radius_m(0.010) == 0.010


def test_damping_coefficient_and_liggghts_gamma_per_unit_mass():
    # zeta 0.5, kn 1 MN/m, m* 0.00807838 kg: c = 2 x 0.5 x sqrt(1e6 x 0.00807838) = 89.880 N s/m
    c = cv.damping_coefficient_n_s_per_m(0.5, 1.0e6, 0.00807838)
    assert c == pytest.approx(89.880, rel=1e-4)
    # hooke/stiffness with absolute_damping off applies c = m* gamman: gamman = 89.880 / 0.00807838 = 11126.0 1/s
    assert cv.hooke_gamma_per_unit_mass_1_s(0.5, 1.0e6, 0.00807838) == pytest.approx(11126.0, rel=1e-4)


def test_restitution_equivalent_of_a_linear_damping_ratio():
    # e = exp(-pi zeta / sqrt(1 - zeta^2)): zeta 0.3 -> exp(-0.942478 / 0.953939) = exp(-0.987986) = 0.372326
    assert cv.linear_restitution_coefficient(0.3) == pytest.approx(0.372326, rel=1e-5)
    # zeta 0.8 -> exp(-2.513274 / 0.6) = exp(-4.188790) = 0.0151646 (RESULTS.md: "continuous-time value 0.0152")
    assert cv.linear_restitution_coefficient(0.8) == pytest.approx(0.0151646, rel=1e-5)
    assert cv.linear_restitution_coefficient(0.0) == 1.0


def test_hertz_restitution_reproduces_demcal_damping_ratio():
    # demcal zeta 0.5: b = 0.5 sqrt(6/5) = 0.547723, ln e = -pi b / sqrt(1 - b^2) = -1.720721 / 0.836660 = -2.056655,
    # e = 0.127881
    e = cv.hertz_restitution_for_damping_ratio(0.5)
    assert e == pytest.approx(0.127881, rel=1e-5)
    # back through LIGGGHTS' own formula: beta = ln e / sqrt(ln^2 e + pi^2), damping 2 zeta_L = -2 sqrt(5/6) beta
    log_e = math.log(e)
    beta = log_e / math.sqrt(log_e ** 2 + math.pi ** 2)
    assert -math.sqrt(5.0 / 6.0) * beta == pytest.approx(0.5, rel=1e-12)
    assert cv.hertz_beta(e) == pytest.approx(beta, rel=1e-12)
    # LIGGGHTS' Hertz dashpot tops out at zeta = sqrt(5/6) = 0.9129 (e -> 0): a higher ratio is refused
    with pytest.raises(ValueError, match="sqrt\\(5/6\\)"):
        cv.hertz_restitution_for_damping_ratio(0.95)


def test_hertz_effective_moduli():
    # E 1 GPa, nu 0.25 on both sides: Y* = E / (2 (1 - nu^2)) = 1e9 / 1.875 = 533.33 MPa,
    # G* = E / (4 (2 - nu)(1 + nu)) = 1e9 / 8.75 = 114.29 MPa
    y, g = cv.hertz_effective_moduli_pa(1e9, 0.25, 1e9, 0.25)
    assert y == pytest.approx(533.333e6, rel=1e-6)
    assert g == pytest.approx(114.2857e6, rel=1e-6)


def test_rolling_stiffness_epsd2_and_epsd():
    # EPSD2: kr = kt R*^2; two 20 mm spheres (R* = 10 mm), kt = 0.86 MN/m: 0.86e6 x 1e-4 = 86 N m/rad
    assert cv.epsd2_rolling_stiffness_n_m_per_rad(0.86e6, 0.010) == pytest.approx(86.0, rel=1e-12)
    # EPSD: kr = 2.25 kn mu_r^2 R*^2 = 2.25 x 0.86e6 x 0.04 x 1e-4 = 7.74 N m/rad, 11 times softer at mu_r 0.2
    assert cv.epsd_rolling_stiffness_n_m_per_rad(0.86e6, 0.2, 0.010) == pytest.approx(7.74, rel=1e-12)


def test_include_carries_the_hand_calculated_pair_values():
    text = render(_material()).text
    # type 1 the spheres, type 2 the walls; row-major 2 x 2 tables
    kn = _pair_values(text, "kn")
    assert kn == pytest.approx([0.86e6, 1.4675768e6, 1.4675768e6, 1.4675768e6], rel=1e-7)
    # gamman = 2 zeta sqrt(kn / m*): sphere-sphere m* = m/2 = 0.0418879 kg: 1.6 sqrt(0.86e6 / 0.0418879) = 7249.8 /s;
    # sphere-wall m* = m = 0.0837758 kg: 1.6 sqrt(1.4675768e6 / 0.0837758) = 6696.7 /s
    gn = _pair_values(text, "gamman")
    assert gn[0] == pytest.approx(7249.8, rel=1e-4)
    assert gn[1] == pytest.approx(6696.7, rel=1e-4)
    assert _pair_values(text, "coefficientFriction") == [0.5, 0.3, 0.3, 0.3]
    assert "absolute_damping off" in text and "tangential_damping on" in text


def test_rolling_and_hertz_include():
    m = _material(effects={"hertz_mindlin": {"young_modulus_pa": 1e9, "poisson_ratio": 0.25},
                           "rolling_epsd2": {"rolling_friction": 0.2}},
                  contact={"damping_ratio_normal": 0.5, "damping_ratio_shear": 0.5})
    text = render(m).text
    assert "pair_style gran model hertz tangential history rolling_friction epsd2" in text
    assert _pair_values(text, "youngsModulus") == [1e9, 1e9]
    assert _pair_values(text, "coefficientRestitution") == pytest.approx([0.127881] * 4, rel=1e-5)
    assert _pair_values(text, "coefficientRollingFriction") == [0.2] * 4


def test_adhesive_contact_is_named_not_faked():
    export = render(_material(effects={"cohesion_adhesive": {"surface_energy_j_m2": 50.0}}))
    pair_line = next(ln for ln in export.text.splitlines() if ln.startswith("pair_style"))
    assert "cohesion" not in pair_line  # no look-alike cohesion model is switched on
    assert "NOT EXACTLY EXPRESSIBLE" in export.text and "sjkr" in export.inexact[0]
    assert not any(ln.startswith("fix demcal_ced") for ln in export.text.splitlines())


def test_shear_damping_other_than_normal_under_hertz_is_reported():
    m = _material(effects={"hertz_mindlin": {"young_modulus_pa": 1e9}},
                  contact={"damping_ratio_normal": 0.5, "damping_ratio_shear": 0.2})
    assert any("Shear damping ratio" in note for note in render(m).inexact)


def test_bad_material_is_refused_with_the_field():
    with pytest.raises(ValueError, match="volume fractions must sum to 1"):
        _material(particles={"spheres": [{"radius_m": 0.02, "volume_fraction": 0.5}]})
    with pytest.raises(ValueError, match="unknown contact effect"):
        _material(effects={"glue": {}})


@pytest.mark.parametrize("effects,clumps", [
    ({"rolling_epsd2": {"rolling_friction": 0.2}}, False),
    ({"hertz_mindlin": {"young_modulus_pa": 1e9, "poisson_ratio": 0.25}, "rolling_epsd": {"rolling_friction": 0.1}}, False),  # zeta 0.8: e at its bound
    ({"rolling_constant_torque": {"rolling_friction": 0.1}, "cohesion_sjkr": {"cohesion_energy_density_j_m3": 1e5}}, True),
])
def test_liggghts_accepts_the_include(effects, clumps):
    """LIGGGHTS reads the include and runs 10 steps with 20 particles (about 1 s each)."""
    require_liggghts()
    from calibration.export.rig_liggghts import check_syntax

    particles = {"spheres": [{"radius_m": 0.02, "volume_fraction": 0.5}],
                 "clumps": [{"name": "pair", "sphere_centres_m": [[0, 0, 0], [0.016, 0, 0]],
                             "sphere_radii_m": [0.012, 0.012], "volume_fraction": 0.5}]} if clumps else {}
    log = check_syntax(render(_material(effects=effects, particles=particles)))
    assert "SYNTAX_OK" in log


def test_hertz_damping_beyond_liggghts_bound_is_reported():
    # LIGGGHTS takes e > 0.05 only: ln 0.05 = -2.995732, beta = -2.995732 / sqrt(8.974412 + 9.869604) = -0.690106,
    # so zeta <= sqrt(5/6) x 0.690106 = 0.62998; demcal's 0.8 is beyond it
    assert cv.hertz_damping_ratio_of_restitution(0.05) == pytest.approx(0.62998, rel=1e-4)
    m = _material(effects={"hertz_mindlin": {"young_modulus_pa": 1e9}})
    export = render(m)
    assert any("at most 0.630" in note for note in export.inexact)
    assert all(e > 0.05 for e in _pair_values(export.text, "coefficientRestitution"))


def test_every_registered_effect_has_an_export():
    """A new effect in engine/effects must get a LIGGGHTS export (or a stated 'not expressible') before a
    calibrated material using it can leave demcal: render refuses unknown effects, and this keeps the
    two lists together."""
    from calibration.export.liggghts import _HANDLED_EFFECTS
    from engine.effects import REGISTRY

    assert set(REGISTRY) == set(_HANDLED_EFFECTS)


def test_clumps_run_at_half_demcals_step_in_liggghts_and_spheres_at_demcals():
    from calibration.export.liggghts import MULTISPHERE_STEP_FACTOR, demcal_timestep_s, render
    from calibration.export.material import from_micro_parameters
    from engine.lab.spec import MicroParameters

    spheres = from_micro_parameters(MicroParameters(), "screening")
    clumps = from_micro_parameters(MicroParameters(clump_aspect_ratio=1.5), "screening")
    assert render(spheres).timestep_s == demcal_timestep_s(spheres)
    assert MULTISPHERE_STEP_FACTOR == 0.5
    exported = render(clumps)
    assert exported.timestep_s == 0.5 * demcal_timestep_s(clumps)
    assert f"variable demcal_dt equal {exported.timestep_s:.10g}" in exported.text
    assert render(clumps, timestep_s=1e-5).timestep_s == 1e-5  # a step the user gives is taken as given
