"""The export's material structure: built from a lab job's parameters, and back for the proof run."""
from __future__ import annotations

import pytest

from calibration.export.material import ExportMaterial, from_micro_parameters
from calibration.export.verify import to_micro_parameters
from engine.lab.spec import MicroParameters


def test_screening_spheres_round_trip_to_the_lab():
    params = MicroParameters(friction_pp=0.5, effects={"rolling_epsd2": {"rolling_friction": 0.2}})
    material = from_micro_parameters(params)
    assert [s.radius_m for s in material.particles.spheres] == [0.020]  # the screening preset's spheres
    back = to_micro_parameters(material)
    assert back.particle_radius_m == 0.020 and back.friction_pp == 0.5
    assert back.effects == {"rolling_epsd2": {"rolling_friction": 0.2}}


def test_screening_clump_round_trip_keeps_the_grain():
    material = from_micro_parameters(MicroParameters(clump_aspect_ratio=1.5))
    back = to_micro_parameters(material)
    # the two-sphere clump of aspect ratio 1.5 keeps the 20 mm sphere's solid volume (engine/lab/shape.py)
    assert back.clump_aspect_ratio == pytest.approx(1.5, rel=1e-12)
    assert back.particle_radius_m == pytest.approx(0.020, rel=1e-12)


def test_thesis_size_ranges_become_volume_weighted_bins():
    material = from_micro_parameters(MicroParameters(), "thesis")
    spheres = material.particles.spheres
    # Table 4.9's sphere class: 15-16.2 mm, 20.8 % of the solid volume, three bins at 15.2, 15.6 and 16.0 mm
    assert [round(s.radius_m * 1000, 3) for s in spheres] == [15.2, 15.6, 16.0]
    assert sum(s.volume_fraction for s in spheres) == pytest.approx(0.208, rel=1e-9)
    assert len(material.particles.clumps) == 6 and len(material.notes) == 3


def test_the_proof_refuses_a_mix_it_cannot_run():
    with pytest.raises(ValueError, match="one sphere size or one two-sphere clump"):
        to_micro_parameters(from_micro_parameters(MicroParameters(), "thesis"))
    with pytest.raises(ValueError, match="damping ratio"):
        to_micro_parameters(ExportMaterial.model_validate({
            "particles": {"solid_density_kg_m3": 2500.0, "spheres": [{"radius_m": 0.02, "volume_fraction": 1.0}]},
            "contact": {"particle_stiffness_n_per_m": 1e6, "wall_stiffness_n_per_m": 1e7, "damping_ratio_normal": 0.5,
                        "damping_ratio_shear": 0.2, "friction_pp": 0.5, "friction_pw": 0.3}}))


def test_a_boolean_is_not_a_number():
    with pytest.raises(ValueError, match="friction_pp"):
        ExportMaterial.model_validate({
            "particles": {"solid_density_kg_m3": 2500.0, "spheres": [{"radius_m": 0.02, "volume_fraction": 1.0}]},
            "contact": {"particle_stiffness_n_per_m": 1e6, "wall_stiffness_n_per_m": 1e7, "damping_ratio_normal": 0.5,
                        "damping_ratio_shear": 0.5, "friction_pp": False, "friction_pw": 0.3}})
