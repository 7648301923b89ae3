"""Bulk density, porosity and voids ratio of a levelled packing (thesis section 4.5).

The height is read as the rig's laboratory read it (``read_packing_height_m``): struck off at the level, or
as the thesis's DEM did from the highest sphere top (``packing_height_m``: at the material's own grain size
at a coarse resolution). The bulk volume is A*H; the reducer nets
the clump lens overlaps out of the solid volume and mass (Eqs. 4.9-4.10; the lens volume is the clump
templates' ``engine.particles.templates.lens_volume_m3``), then applies
Eq. 4.2 (rho_b = m_b / V_b), Eq. 4.4 (e = rho_p / rho_b - 1) and Eq. 4.7 (n = e / (e + 1)).
Porosity is returned as a fraction (SI), not in percent.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PackingState:
    """What the fill reducer needs from a packing: solid volume net of lenses, height, area."""

    solid_volume_m3: float
    particle_density_kg_m3: float
    packing_height_m: float
    container_area_m2: float
    particle_count: int


def packing_height_m(sphere_centres_z_m, sphere_radii_m, scale_factor: float = 1.0) -> float:
    """The thesis's packing height (section 4.5.4: the highest sphere's centre plus its radius), with each radius
    at the material's own size: at a coarse resolution (sizes x ``scale_factor``) the levelled grains' centres
    still reach the level, but a radius s times the material's would add (s - 1) r to H and take it off the
    bulk density (361 mm for a 330 mm level at x 2 in the thesis box; docs/lab.md). As measured (s = 1) this is
    the highest sphere top."""
    z = np.asarray(sphere_centres_z_m, float)
    r = np.asarray(sphere_radii_m, float)
    if not scale_factor >= 1.0:
        raise ValueError(f"scale_factor must be >= 1 (a coarse-graining factor), got {scale_factor}")
    return float(np.max(z + r / scale_factor))


def read_packing_height_m(rule: str, level_m: float, sphere_centres_z_m, sphere_radii_m,
                          scale_factor: float = 1.0) -> float:
    """The packing height by ``rule`` (``engine.lab.rigs.Fill.height_rule``). "struck_off": the level itself, as
    a laboratory reads a packing struck off with a straightedge across the brim (its bulk volume the
    container's to the level; the thesis's 329-330 mm for a 330 mm level, Table 4.5); the bodies whose centre
    of mass stood above it were removed, which keeps the solid volume below the level unbiased.
    "highest_sphere_top": the thesis's DEM rule (``packing_height_m``), about one grain radius above the level
    (Table 4.10: 340 mm DEM against 329 mm measured)."""
    if rule == "struck_off":
        return float(level_m)
    if rule == "highest_sphere_top":
        return packing_height_m(sphere_centres_z_m, sphere_radii_m, scale_factor)
    raise ValueError(f"unknown packing height rule {rule!r} (struck_off, highest_sphere_top)")


def bulk_properties(state: PackingState) -> dict[str, float]:
    """Thesis Eqs. 4.2, 4.4, 4.7 on one packing; keys are the fill's declared quantity names (engine/lab/labtests/fill.py)."""
    if state.packing_height_m <= 0 or state.container_area_m2 <= 0:
        raise ValueError("packing height and container area must be positive")
    bulk_volume_m3 = state.container_area_m2 * state.packing_height_m
    bulk_mass_kg = state.solid_volume_m3 * state.particle_density_kg_m3
    bulk_density = bulk_mass_kg / bulk_volume_m3
    if bulk_density <= 0:
        raise ValueError("empty packing: no solid volume below the packing height")
    voids_ratio = state.particle_density_kg_m3 / bulk_density - 1.0
    porosity = voids_ratio / (voids_ratio + 1.0)
    return {
        "bulk_density_kg_m3": bulk_density,
        "porosity": porosity,
        "voids_ratio": voids_ratio,
        "packing_height_m": state.packing_height_m,
        "bulk_mass_kg": bulk_mass_kg,
        "particle_count": float(state.particle_count),
    }
