"""Confined compression test reduction (thesis section 3.4 and Eqs. 4.11-4.12).

Each loading branch gives a confined modulus E' = d(sigma_n)/d(eps_n) over its central part
(the thesis read the upper and lower points of the centre region off a plot; a least-squares
slope over the same region is the reproducible version of that reading). The first cycle is
compaction and is left out; E' is the mean over cycles 2..N and k_b = A / H * E'.
E' is also given per stress window, because a missing non-linear contact law shows up as a
modulus that grows with stress level, which one averaged number hides.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


def split_cycles(strain: np.ndarray, hysteresis_fraction: float = 0.05) -> list[tuple[int, int]]:
    """Index ranges [start, end] of the loading branches (strain rising) of a cyclic record.

    Turning points are found with a hysteresis of ``hysteresis_fraction`` of the strain range
    so that noise on a branch does not split it.
    """
    strain = np.asarray(strain, dtype=float)
    if strain.size < 3:
        return []
    threshold = hysteresis_fraction * float(np.ptp(strain))
    if threshold <= 0:
        return []
    branches: list[tuple[int, int]] = []
    i_min = 0
    i_max = 0
    rising = True
    for i in range(1, strain.size):
        if rising:
            if strain[i] > strain[i_max]:
                i_max = i
            elif strain[i_max] - strain[i] > threshold:
                branches.append((i_min, i_max))
                rising = False
                i_min = i
        else:
            if strain[i] < strain[i_min]:
                i_min = i
            elif strain[i] - strain[i_min] > threshold:
                rising = True
                i_max = i
    if rising and strain[i_max] - strain[i_min] > threshold:
        branches.append((i_min, i_max))
    return branches


def _slope(x: np.ndarray, y: np.ndarray) -> float:
    if x.size < 2 or np.ptp(x) <= 0:
        return float("nan")
    return float(np.polyfit(x, y, 1)[0])


@dataclass
class CctReduction:
    modulus_per_cycle_pa: list[float]
    confined_modulus_pa: float
    bulk_stiffness_n_per_m: float
    window_stress_mid_pa: list[float] = field(default_factory=list)
    window_modulus_pa: list[float] = field(default_factory=list)


def reduce_cct(
    strain: np.ndarray,
    normal_stress_pa: np.ndarray,
    container_area_m2: float,
    packing_height_m: float,
    central_fraction: tuple[float, float] = (0.25, 0.75),
    first_cycle_used: int = 2,
    stress_windows: int = 5,
) -> CctReduction:
    """Reduce a cyclic stress-strain record to E' (Eq. 4.11), k_b (Eq. 4.12) and E'(sigma).

    ``central_fraction`` bounds the central part of each loading branch as fractions of that
    branch's peak stress. Cycles are numbered from 1; cycles before ``first_cycle_used`` are
    compaction and are skipped (if the record has fewer cycles, all are used).
    """
    strain = np.asarray(strain, dtype=float)
    stress = np.asarray(normal_stress_pa, dtype=float)
    if strain.shape != stress.shape:
        raise ValueError("strain and stress must have the same length")
    lo, hi = central_fraction
    if not 0 <= lo < hi <= 1:
        raise ValueError("central_fraction must satisfy 0 <= lower < upper <= 1")
    branches = split_cycles(strain)
    if not branches:
        raise ValueError("no loading branch found in the CCT record")
    moduli = []
    for start, end in branches:
        s, e = stress[start:end + 1], strain[start:end + 1]
        peak = float(np.max(s))
        mask = (s >= lo * peak) & (s <= hi * peak)
        moduli.append(_slope(e[mask], s[mask]))
    used_branches = branches[first_cycle_used - 1:] if len(branches) >= first_cycle_used else branches
    used = moduli[first_cycle_used - 1:] if len(moduli) >= first_cycle_used else moduli
    used_finite = [m for m in used if np.isfinite(m)]
    if not used_finite:
        raise ValueError("loading branches too short to fit a modulus")
    modulus = float(np.mean(used_finite))
    stiffness = container_area_m2 / packing_height_m * modulus

    peak_all = max(float(np.max(stress[a:b + 1])) for a, b in used_branches)
    edges = np.linspace(0.0, peak_all, stress_windows + 1)
    mids, window_moduli = [], []
    for w in range(stress_windows):
        per_cycle = []
        for start, end in used_branches:
            s, e = stress[start:end + 1], strain[start:end + 1]
            mask = (s >= edges[w]) & (s <= edges[w + 1])
            m = _slope(e[mask], s[mask]) if np.count_nonzero(mask) >= 3 else float("nan")
            if np.isfinite(m):
                per_cycle.append(m)
        if per_cycle:
            mids.append(float(0.5 * (edges[w] + edges[w + 1])))
            window_moduli.append(float(np.mean(per_cycle)))
    return CctReduction(
        modulus_per_cycle_pa=[float(m) for m in moduli],
        confined_modulus_pa=modulus,
        bulk_stiffness_n_per_m=float(stiffness),
        window_stress_mid_pa=mids,
        window_modulus_pa=window_moduli,
    )
