"""The elastic-plastic rolling spring shared by EPSD and EPSD2 (Ai et al. 2011, model type C).

Not an effect itself: the two models differ only in the spring's stiffness and EPSD's dashpot.
"""
from __future__ import annotations

import math

from numba import njit

from ..springs import onto_plane_keep_length


@njit(cache=True, inline='always')
def rolling_velocity(n0, n1, n2, w0, w1, w2):
    """The relative angular velocity without its twisting part (the part along n)."""
    wn = w0 * n0 + w1 * n1 + w2 * n2
    return w0 - wn * n0, w1 - wn * n1, w2 - wn * n2


@njit(cache=True, inline='always')
def spring_torque(hist, h0, n0, n1, n2, w0, w1, w2, kr, limit, dt):
    """Advance the spring torque on i by -k_r w_roll dt and cap its magnitude at ``limit``.

    The stored torque is first rotated into the current tangent plane, keeping its magnitude.
    Returns the torque and whether it stayed below the cap (not fully mobilised): EPSD's dashpot
    acts only then.
    """
    r0, r1, r2 = rolling_velocity(n0, n1, n2, w0, w1, w2)
    m0, m1, m2 = onto_plane_keep_length(hist[h0], hist[h0 + 1], hist[h0 + 2], n0, n1, n2)
    m0 -= kr * r0 * dt
    m1 -= kr * r1 * dt
    m2 -= kr * r2 * dt
    mag = math.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    elastic = mag <= limit
    if not elastic:
        s = limit / mag if mag > 0.0 else 0.0
        m0 *= s
        m1 *= s
        m2 *= s
    hist[h0] = m0
    hist[h0 + 1] = m1
    hist[h0 + 2] = m2
    return m0, m1, m2, elastic
