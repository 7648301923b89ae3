"""Particles: clump templates with overlap-corrected mass properties, size and shape distributions, packings."""
from .templates import ClumpTemplate, double_clump, from_spheres, pyramid, sphere  # noqa: F401
from .generation import BoxRegion, CylinderRegion, InsertionError, Packing, insert_random, lattice  # noqa: F401
