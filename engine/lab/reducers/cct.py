"""Confined compression test reduction (thesis section 3.4 and Eqs. 4.11-4.12).

Each loading branch gives a confined modulus E' = d(sigma_n)/d(eps_n) over its central part
(the thesis read the upper and lower points of the centre region off a plot; a least-squares
slope over the same region is the reproducible version of that reading). The first cycle is
compaction and is left out; E' is the mean over cycles 2..N and k_b = A / H * E'.
E' is also given per stress window, because a missing non-linear contact law shows up as a
modulus that grows with stress level, which one averaged number hides: either in equal windows from
0 to the peak, or, when the user measured E' at given stresses, as the tangent modulus at exactly
those stresses (``tangent_modulus_at``), so that simulation and measurement meet one to one.
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


# half-width of the window round a requested stress s, as a fraction of s (see tangent_modulus_at)
TANGENT_WINDOW_HALF_WIDTH = 0.25


def tangent_modulus_at(
    strain: np.ndarray,
    normal_stress_pa: np.ndarray,
    branches: list[tuple[int, int]],
    stress_pa: float,
    half_width_fraction: float = TANGENT_WINDOW_HALF_WIDTH,
) -> float:
    """Tangent confined modulus d(sigma)/d(eps) at ``stress_pa`` on the given loading branches (Pa).

    Per branch, a least-squares line of stress on strain through the points with stress within
    s (1 -+ h), h = ``half_width_fraction``; the mean over the branches that give a slope. NaN when no
    branch has 3 points in its window: no value rather than a wrong one.

    Why +-25 % of s: a record has noise (force chatter of a few-hundred-grain packing) that a narrow
    window amplifies, and curvature that a wide one turns into bias. For a power-law loading branch
    sigma ~ eps^n sampled evenly in strain (constant lid speed), the least-squares slope over
    s (1 -+ h) reads the tangent at s low by 0.4 % for a Hertzian packing (n = 3/2, E' ~ sigma^(1/3)),
    0.8 % for n = 2 and 1.3 % for n = 3 at h = 0.25 (0.07-0.2 % at h = 0.1, 1.1-3.4 % at h = 0.4),
    independent of s; the window then holds half the points of the central 25-75 % band at s = 0.5 of
    the peak. A window proportional to s keeps the bias the same at every stress level, which a fixed
    width in Pa would not.
    The window stays centred on s: near a branch's peak it is narrowed to (s - (peak - s), peak) on both
    sides rather than clipped on one side, because a one-sided window estimates the slope at its own
    centre, not at s.
    """
    strain = np.asarray(strain, dtype=float)
    stress = np.asarray(normal_stress_pa, dtype=float)
    s0 = float(stress_pa)
    per_branch = []
    for start, end in branches:
        s, e = stress[start:end + 1], strain[start:end + 1]
        peak = float(np.max(s))
        half = min(half_width_fraction * s0, peak - s0)
        if not half > 0:
            continue
        mask = (s >= s0 - half) & (s <= s0 + half)
        if np.count_nonzero(mask) < 3:
            continue
        m = _slope(e[mask], s[mask])
        if np.isfinite(m):
            per_branch.append(m)
    return float(np.mean(per_branch)) if per_branch else float("nan")


# the first part of a small unloading's stress drop that unload_reload_modulus leaves out
UNLOAD_RELOAD_SKIP_FRACTION = 0.2


def unload_reload_modulus(strain: np.ndarray, normal_stress_pa: np.ndarray,
                          skip_fraction: float = UNLOAD_RELOAD_SKIP_FRACTION) -> float:
    """The unload-reload modulus E_ur (Pa) of one small unloading: the least-squares slope of stress on strain.

    ``strain`` and ``normal_stress_pa`` run from the held stress down to the end of the unloading. The first
    ``skip_fraction`` of the stress drop is left out: reversing the lid sends a stress jump of 2 sqrt(rho_b E) v
    through the packing before the quasi-static response takes over, a step that would read as stiffness.
    NaN when fewer than 3 samples remain (no value rather than a wrong one).

    Why it is measured: on unloading the contacts stick, so the slope is the packing's elastic stiffness at that
    stress on a fixed contact network; the loading E' also counts the network's growth and the contacts that
    slide. A Hertzian contact's stiffness grows as F^(1/3), so at a fixed network E_ur ~ sigma^(1/3) for Hertz and
    is flat for linear springs (Goddard 1990; sands' unload-reload moduli grow as sigma^0.5, Schanz et al. 1999);
    the loading E' of a loose packing grows about as much under either law (docs/diagnosis.md, hertz_strong).
    """
    strain = np.asarray(strain, dtype=float)
    stress = np.asarray(normal_stress_pa, dtype=float)
    if strain.size < 3:
        return float("nan")
    top, bottom = float(stress[0]), float(np.min(stress))
    kept = stress <= top - skip_fraction * (top - bottom)
    return _slope(strain[kept], stress[kept]) if np.count_nonzero(kept) >= 3 else float("nan")


@dataclass
class CctReduction:
    """E' per cycle and its mean over cycles 2..N (Pa), k_b (N/m), and E' against stress (Pa).

    ``window_stress_mid_pa`` / ``window_modulus_pa``: E' per stress window, keyed by the window's mid
    stress (equal windows 0..peak), or exactly the requested stresses when ``window_stresses_pa`` was
    given; a stress where no loading branch had 3 points in its window is left out of both lists.
    """

    modulus_per_cycle_pa: list[float]
    confined_modulus_pa: float
    bulk_stiffness_n_per_m: float
    window_stress_mid_pa: list[float] = field(default_factory=list)
    window_modulus_pa: list[float] = field(default_factory=list)


@dataclass
class UnloadReload:
    """The unload-reload moduli E_ur (Pa) at the held stresses (Pa); a stress whose unloading gave no modulus
    (``unload_reload_modulus`` NaN) is left out of both lists."""

    stress_pa: list[float] = field(default_factory=list)
    modulus_pa: list[float] = field(default_factory=list)


def reduce_unload_reload(strain: np.ndarray, normal_stress_pa: np.ndarray, stresses_pa: list[float],
                         ranges: list[tuple[int, int]]) -> UnloadReload:
    """E_ur per held stress from the lid's record: ``ranges`` are the record's index ranges of the small
    unloadings, one per stress of ``stresses_pa``."""
    out = UnloadReload()
    for target, (a, b) in zip(stresses_pa, ranges):
        modulus = unload_reload_modulus(strain[a:b], normal_stress_pa[a:b])
        if np.isfinite(modulus):
            out.stress_pa.append(float(target))
            out.modulus_pa.append(modulus)
    return out


def reduce_cct(
    strain: np.ndarray,
    normal_stress_pa: np.ndarray,
    container_area_m2: float,
    packing_height_m: float,
    central_fraction: tuple[float, float] = (0.25, 0.75),
    first_cycle_used: int = 2,
    stress_windows: int = 5,
    window_stresses_pa: list[float] | None = None,
    window_half_width_fraction: float = TANGENT_WINDOW_HALF_WIDTH,
) -> CctReduction:
    """Reduce a cyclic stress-strain record to E' (Eq. 4.11), k_b (Eq. 4.12) and E'(sigma).

    ``central_fraction`` bounds the central part of each loading branch as fractions of that
    branch's peak stress. Cycles are numbered from 1; cycles before ``first_cycle_used`` are
    compaction and are skipped (if the record has fewer cycles, all are used).
    E'(sigma): in ``stress_windows`` equal windows from 0 to the peak, or, with ``window_stresses_pa``,
    the tangent modulus at each of those stresses (``tangent_modulus_at``), reported under the very
    float given so that it meets a measurement at that stress exactly.
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

    if window_stresses_pa is not None:
        mids, window_moduli = [], []
        for target in window_stresses_pa:
            m = tangent_modulus_at(strain, stress, used_branches, target, window_half_width_fraction)
            if np.isfinite(m):
                mids.append(target)
                window_moduli.append(m)
        return CctReduction(
            modulus_per_cycle_pa=[float(m) for m in moduli],
            confined_modulus_pa=modulus,
            bulk_stiffness_n_per_m=float(stiffness),
            window_stress_mid_pa=mids,
            window_modulus_pa=window_moduli,
        )

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
