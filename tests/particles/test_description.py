"""Particles as data: the model validates what a user sends (naming the field) and builds the engine's mix."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from pydantic import ValidationError

from engine.particles import distributions as dist
from engine.particles.description import Particles, thesis_particles

BUNDLED_MATERIAL = Path(__file__).parents[2] / "service" / "materials" / "thesis_coarse_aggregate.json"


def _loc(body: dict) -> tuple:
    with pytest.raises(ValidationError) as err:
        Particles.model_validate(body)
    return err.value.errors()[0]["loc"]


def test_thesis_particles_are_table_4_2():
    p = thesis_particles()
    assert p.solid_density_kg_m3 == 2586.5  # section 4.5.2, water displacement
    assert [(s.shape, s.volume_fraction) for s in p.shapes] == [("pyramid", 0.375), ("elongated", 0.417),
                                                               ("sphere", 0.208)]
    assert [p.size_of(s).radius_range_m for s in p.shapes] == [(0.0075, 0.0105), (0.012, 0.015), (0.015, 0.0162)]
    mix = p.shape_mix()
    assert [c.shape for c in mix.components] == ["pyramid", "double_clump", "sphere"]
    assert mix.components[1].overlap_factor == 1.0  # aspect ratio 2: C = 1, touching spheres (Table 4.2)
    # the same mix distributions.thesis_shape_mix has always built
    assert mix == dist.thesis_shape_mix()


def test_bundled_material_carries_the_thesis_particles():
    material = json.loads(BUNDLED_MATERIAL.read_text())
    assert Particles.model_validate(material["particles"]) == thesis_particles()
    assert material["rig"] == "thesis-590mm-shear-box"


def test_sieve_curve_mix_reproduces_its_curve():
    """8-16 mm gravel: half the mass below 11.2 mm. A large sample's mass passing matches the curve."""
    body = {"solid_density_kg_m3": 2650.0,
            "size": {"form": "sieve", "sieve_sizes_m": [0.008, 0.0112, 0.016], "passing_fractions": [0.0, 0.5, 1.0]},
            "shapes": [{"shape": "sphere", "volume_fraction": 0.6},
                       {"shape": "elongated", "aspect_ratio": 1.5, "volume_fraction": 0.4}]}
    p = Particles.model_validate(body)
    assert p.smallest_particle_size_m == pytest.approx(0.008) and p.largest_particle_size_m == pytest.approx(0.016)
    assert p.shape_mix().components[1].overlap_factor == pytest.approx(0.5)
    sieve = p.size_of(p.shapes[0]).distribution()
    radii = sieve.sample(np.random.default_rng(1), 20_000)
    assert sieve.mass_passing(radii)[1] == pytest.approx(0.5, abs=0.02)


def test_custom_clump_template_from_its_spheres():
    # two touching equal spheres: the union is two spheres' volume (no lens)
    body = {"size": {"form": "constant", "radius_m": 0.01},
            "shapes": [{"shape": "custom", "volume_fraction": 1.0, "sphere_centres_m": [[0, 0, 0], [0.02, 0, 0]],
                        "sphere_radii_m": [0.01, 0.01]}]}
    p = Particles.model_validate(body)
    assert p.shapes[0].template.volume_m3 == pytest.approx(2 * 4 / 3 * np.pi * 0.01 ** 3, rel=1e-9)
    # end on, it passes a hole of one sphere's diameter (20 mm), though it is 40 mm long
    assert p.largest_particle_size_m == pytest.approx(0.02)


@pytest.mark.parametrize("body, loc", [
    ({"shapes": [{"shape": "sphere", "volume_fraction": 0.5, "size": {"form": "constant", "radius_m": 0.01}}]}, ()),
    ({"shapes": [{"shape": "sphere", "volume_fraction": 1.0, "size": {"form": "constant", "radius_m": -0.01}}]},
     ("shapes", 0, "size", "constant", "radius_m")),
    ({"shapes": [{"shape": "elongated", "volume_fraction": 1.0, "size": {"form": "constant", "radius_m": 0.01}}]},
     ("shapes", 0)),
    ({"shapes": [{"shape": "sphere", "volume_fraction": 1.0}]}, ()),  # no size anywhere
    ({"size": {"form": "sieve", "sieve_sizes_m": [0.016, 0.008], "passing_fractions": [0.0, 1.0]},
      "shapes": [{"shape": "sphere", "volume_fraction": 1.0}]}, ("size", "sieve")),
    ({"size": {"form": "sieve", "sieve_sizes_m": [0.008, 0.016], "passing_fractions": [0.0, 0.9]},
      "shapes": [{"shape": "sphere", "volume_fraction": 1.0}]}, ("size", "sieve")),
    ({"solid_density_kg_m3": 30_000.0, "size": {"form": "constant", "radius_m": 0.01},
      "shapes": [{"shape": "sphere", "volume_fraction": 1.0}]}, ("solid_density_kg_m3",)),
    ({"size": {"form": "constant", "radius_m": 0.01},
      "shapes": [{"shape": "sphere", "volume_fraction": 1.0, "aspect_ratio": 1.5}]}, ("shapes", 0)),
])
def test_bad_particles_are_refused_naming_the_field(body, loc):
    assert _loc(body)[:len(loc)] == loc
