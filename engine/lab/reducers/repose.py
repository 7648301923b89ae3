"""Angle of repose from a pile at rest, measured in azimuthal sectors (thesis section 5.2).

The experiment read the angle with a protractor at eight places round the pile (Table 5.1);
the thesis's simulation read four from front and side views (Table 5.2). Here each of
``sectors`` azimuthal sectors gets a free-surface profile (highest particle top per radial
bin of one particle diameter) and a straight line fitted to the flank: the contiguous bins
from the peak outward while the surface stands above the toe (the layer of grains that ran
out over the floor, or ``flank_fraction[0]`` of the peak), leaving out a rounded cap above
``flank_fraction[1]`` of the peak when enough bins remain. A protractor reads the same part
of the slope. The first bin at the toe is not part of the flank: on a pile a few grains high
the step from the last flank grain down to the run-out layer is one grain high over one bin,
whatever the slope, and fitting it reads the grain's shape instead of the pile's angle.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class ReposeReduction:
    angle_of_repose_deg: float
    sector_angles_deg: list[float]
    profile_radius_m: list[list[float]]
    profile_height_m: list[list[float]]


def angle_of_repose(
    positions_m: np.ndarray,
    radii_m: np.ndarray,
    centre_xy_m: tuple[float, float] = (0.0, 0.0),
    floor_z_m: float = 0.0,
    sectors: int = 8,
    bin_width_m: float | None = None,
    flank_fraction: tuple[float, float] = (0.2, 0.8),
    toe_height_m: float = 0.0,
) -> ReposeReduction:
    """``toe_height_m``: heights up to this (the layer of grains that ran out over the floor) are
    not part of the flank, whatever fraction of the peak they are."""
    pos = np.asarray(positions_m, dtype=float).reshape(-1, 3)
    radii = np.asarray(radii_m, dtype=float).reshape(-1)
    if pos.shape[0] != radii.size or radii.size == 0:
        raise ValueError("positions and radii must describe the same, non-empty set of spheres")
    if bin_width_m is None:
        bin_width_m = 2.0 * float(np.mean(radii))
    dx, dy = pos[:, 0] - centre_xy_m[0], pos[:, 1] - centre_xy_m[1]
    rho = np.hypot(dx, dy)
    azimuth = np.mod(np.arctan2(dy, dx), 2 * np.pi)
    top = pos[:, 2] + radii - floor_z_m
    sector_of = np.minimum((azimuth / (2 * np.pi) * sectors).astype(int), sectors - 1)
    lo, hi = flank_fraction
    angles, prof_r, prof_h = [], [], []
    for s in range(sectors):
        sel = sector_of == s
        if not np.any(sel):
            angles.append(float("nan"))
            prof_r.append([])
            prof_h.append([])
            continue
        bins = (rho[sel] / bin_width_m).astype(int)
        heights = np.full(bins.max() + 1, -np.inf)
        np.maximum.at(heights, bins, top[sel])
        filled = np.isfinite(heights)
        r_mid = (np.arange(heights.size) + 0.5) * bin_width_m
        r_s, h_s = r_mid[filled], heights[filled]
        prof_r.append(r_s.tolist())
        prof_h.append(h_s.tolist())
        peak = float(np.max(h_s))
        i_peak = int(np.argmax(h_s))
        # the flank: contiguous bins outward from the peak while the surface is above the toe
        j = i_peak + 1
        while j < h_s.size and h_s[j] > max(lo * peak, toe_height_m):
            j += 1
        idx = np.arange(i_peak, j)
        mask = np.zeros(h_s.size, bool)
        mask[idx] = True
        trimmed = mask & (h_s <= hi * peak)
        if np.count_nonzero(trimmed) >= 3:  # a large pile: leave out its rounded cap
            mask = trimmed
        if np.count_nonzero(mask) < 2:
            angles.append(float("nan"))
            continue
        slope = float(np.polyfit(r_s[mask], h_s[mask], 1)[0])
        angles.append(float(np.degrees(np.arctan(max(-slope, 0.0)))))
    finite = [a for a in angles if np.isfinite(a)]
    if not finite:
        raise ValueError("no sector has a measurable flank: the pile is flatter than one particle layer")
    return ReposeReduction(float(np.mean(finite)), angles, prof_r, prof_h)
