"""Small vector helpers shared by the base contact law and the effects (inlined into the kernels)."""
from __future__ import annotations

import math

from numba import njit


@njit(cache=True, inline='always')
def onto_plane_keep_length(x0, x1, x2, n0, n1, n2):
    """Project a stored spring (force or torque) onto the plane normal to n, keeping its length.

    Contact frames turn between steps; the spring must stay tangent without gaining or losing
    stored energy (the incremental spring of Cundall & Strack, as PFC and LIGGGHTS do).
    """
    xn = x0 * n0 + x1 * n1 + x2 * n2
    if xn == 0.0:
        return x0, x1, x2
    sq_old = x0 * x0 + x1 * x1 + x2 * x2
    x0 -= xn * n0
    x1 -= xn * n1
    x2 -= xn * n2
    sq_new = x0 * x0 + x1 * x1 + x2 * x2
    if sq_new > 0.0:
        # one root of the ratio instead of two lengths (this runs for every touching contact)
        s = math.sqrt(sq_old / sq_new)
        return x0 * s, x1 * s, x2 * s
    return x0, x1, x2
