"""Anchor pull-out reduction (thesis section 5.3): the peak resistance force and where it occurs."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class AnchorReduction:
    peak_pull_force_n: float
    displacement_at_peak_m: float


def reduce_anchor(displacement_m, pull_force_n, span: int = 1) -> AnchorReduction:
    """Peak of the (optionally moving-averaged) force-displacement record.

    The thesis compared raw peaks (Table 5.5); ``span`` > 1 smooths single-step contact spikes.
    """
    from engine.lab.reducers.dst import moving_average

    d = np.asarray(displacement_m, dtype=float)
    f = np.asarray(pull_force_n, dtype=float)
    if d.size == 0 or d.size != f.size:
        raise ValueError("anchor record must be non-empty with equal-length columns")
    f_s = moving_average(f, span) if span > 1 else f
    i = int(np.argmax(f_s))
    return AnchorReduction(float(f_s[i]), float(d[i]))
