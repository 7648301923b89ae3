"""Angle of repose from a pile at rest, measured in azimuthal sectors (thesis section 5.2).

The experiment read the angle with a protractor at eight places round the pile (Table 5.1);
the thesis's simulation read four from front and side views (Table 5.2). Here each of
``sectors`` directions gets a free-surface profile and a straight line fitted to its flank.

The profile is what a protractor laid on the flank touches: the highest particle top per bin
of distance along the direction, over a wedge of +-360/sectors degrees round it (a side view
of that part of the pile). On a cone the wedge's envelope is the cone's own generatrix; using
the wedge rather than a thin sector means every bin sees many grains, so one hole or one
proud grain on a pile a few grains high does not set the sector's angle.

The flank runs outward from the last bin of the cap to the toe. The toe is the first bin at
or below the foot level: the layer of grains that ran out over the floor (``toe_height_m``) or
``flank_fraction[0]`` of the peak; it is not part of the flank, since on a pile a few grains
high the step from the last flank grain down to the run-out layer is one grain high over one
bin whatever the slope. The cap is the rounded or flat top, every bin out to the last one
standing higher than ``flank_fraction[1]`` of the way from the foot level up to the peak: a
pile only a few grains high keeps a flat top where the last of the column came down, and a
line through it reads the top, not the slope.
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


def _flank_angle_deg(r_s: np.ndarray, h_s: np.ndarray, lo: float, hi: float, toe_height_m: float) -> float:
    i_peak = int(np.argmax(h_s))
    peak = float(h_s[i_peak])
    foot = max(lo * peak, toe_height_m)
    if peak <= foot:  # nothing stands above the run-out layer
        return float("nan")
    j = i_peak + 1  # first bin of the toe
    while j < h_s.size and h_s[j] > foot:
        j += 1
    # the cap: from the peak out to the last bin above `hi` of the way from the foot up to the peak
    cap = foot + hi * (peak - foot)
    first = i_peak + int(np.nonzero(h_s[i_peak:j] > cap)[0][-1]) + 1
    if j - first < 2:  # a short flank: take the cap's last bin too
        first = max(first - 1, i_peak)
    if j - first < 2:
        return float("nan")
    slope = float(np.polyfit(r_s[first:j], h_s[first:j], 1)[0])
    return float(np.degrees(np.arctan(max(-slope, 0.0))))


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
    not part of the flank, whatever fraction of the peak they are. Sector k (0-based) looks along
    azimuth (k + 1/2) 360/sectors degrees."""
    pos = np.asarray(positions_m, dtype=float).reshape(-1, 3)
    radii = np.asarray(radii_m, dtype=float).reshape(-1)
    if pos.shape[0] != radii.size or radii.size == 0:
        raise ValueError("positions and radii must describe the same, non-empty set of spheres")
    if sectors < 1:
        raise ValueError("sectors must be at least 1")
    if bin_width_m is None:
        bin_width_m = 2.0 * float(np.mean(radii))
    dx, dy = pos[:, 0] - centre_xy_m[0], pos[:, 1] - centre_xy_m[1]
    rho = np.hypot(dx, dy)
    azimuth = np.arctan2(dy, dx)
    top = pos[:, 2] + radii - floor_z_m
    half_wedge = min(2 * np.pi / sectors, np.pi / 2)
    lo, hi = flank_fraction
    angles, prof_r, prof_h = [], [], []
    for s in range(sectors):
        direction = (s + 0.5) * 2 * np.pi / sectors
        off = np.mod(azimuth - direction + np.pi, 2 * np.pi) - np.pi
        sel = np.abs(off) <= half_wedge
        along = rho * np.cos(off)
        if not np.any(sel):
            angles.append(float("nan"))
            prof_r.append([])
            prof_h.append([])
            continue
        bins = np.maximum(along[sel] / bin_width_m, 0.0).astype(int)
        heights = np.full(bins.max() + 1, -np.inf)
        np.maximum.at(heights, bins, top[sel])
        filled = np.isfinite(heights)
        r_mid = (np.arange(heights.size) + 0.5) * bin_width_m
        r_s, h_s = r_mid[filled], heights[filled]
        prof_r.append(r_s.tolist())
        prof_h.append(h_s.tolist())
        angles.append(_flank_angle_deg(r_s, h_s, lo, hi, toe_height_m))
    finite = [a for a in angles if np.isfinite(a)]
    if not finite:
        raise ValueError("no sector has a measurable flank: the pile is flatter than one particle layer")
    return ReposeReduction(float(np.mean(finite)), angles, prof_r, prof_h)
