"""Particle shape as a calibration parameter: screening spheres elongated into two-sphere clumps.

Why: shape is the first physical effect a sphere model misses for a crushed aggregate (Azema & Radjai
2010: strength and dilatancy rise with elongation; the packing fraction is non-monotonic), and
the missing-physics diagnosis needs a continuous strength for it. ``clump_aspect_ratio`` (length
over width of a two-sphere clump, 1 = sphere) is that strength; the screening fidelity builds its
grains from it, keeping each grain's solid volume equal to the sphere it replaces so that a change
of shape is not also a change of size.
"""
from __future__ import annotations

from engine.effects.base import Candidate

# EDEM's angle-of-repose kit uses two-sphere clumps at aspect ratio 1.5; ballast models 1.2-2.0
CANDIDATE = Candidate(
    name="particle_shape", title="particle shape (elongation)", factor="clump_aspect_ratio",
    unit="1", plausible_range=(1.2, 2.0), step=0.3, off_value=1.0,
    fingerprint={"bulk_density": "-", "modulus_level": "+-", "friction_angle": "+", "dilatancy": "++",
                 "angle_of_repose": "+", "pull_force": "+"},
    physics="Elongated, interlocking grains dilate more and resist shear more than spheres: friction "
            "angle, dilatancy (lid rise), angle of repose and pull-out rise and the packing loosens. "
            "It looks like rolling resistance (Estrada et al. 2011) but with a larger dilatancy "
            "deficit; the two form an alias group that dilatancy per load separates.",
)
