"""Direct shear test reduction (thesis sections 3.3.2 and 4.7.2, Eqs. 3.1, 3.2, 3.8).

Stresses are smoothed with a centred moving average (21 points in the thesis), residual
shear and normal stresses are the means over a shear-strain window (8-10 % in the thesis,
15-17 % for its offset variant in Appendix C), the Coulomb line through the residual points
gives phi and c, and the dilatancy angle is the slope of lid rise against shear displacement
over the same window.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


def moving_average(values: np.ndarray, span: int = 21) -> np.ndarray:
    """Centred moving average; the span shrinks symmetrically near the ends (as Matlab's smooth)."""
    values = np.asarray(values, dtype=float)
    if span < 1 or span % 2 == 0:
        raise ValueError("span must be a positive odd number")
    n = values.size
    half = span // 2
    out = np.empty(n)
    csum = np.concatenate(([0.0], np.cumsum(values)))
    for i in range(n):
        h = min(half, i, n - 1 - i)
        out[i] = (csum[i + h + 1] - csum[i - h]) / (2 * h + 1)
    return out


def _window_mask(shear_strain: np.ndarray, window: tuple[float, float]) -> np.ndarray:
    lo, hi = window
    if not lo < hi:
        raise ValueError("strain window must have lower < upper")
    mask = (shear_strain >= lo) & (shear_strain <= hi)
    if np.count_nonzero(mask) < 2:
        reached = float(np.max(shear_strain)) if shear_strain.size else 0.0
        raise ValueError(
            f"shear record reaches strain {reached:.4f}; the residual window {lo:.3f}-{hi:.3f} needs at least 2 points"
        )
    return mask


def samples_needed_past_window(span: int) -> int:
    """Samples a shear record needs beyond the residual window's upper strain before ``reduce_dst`` reads
    nothing more from it: the moving average of the window's last sample reaches ``span // 2`` samples
    ahead, and at least one sample past the window shows where the window ends. A record stopped there
    reduces to the same values, to the bit, as one that goes on (``options.stop_after_reduced``)."""
    return max(span // 2, 1)


def window_mean(shear_strain: np.ndarray, values: np.ndarray, window: tuple[float, float]) -> float:
    shear_strain = np.asarray(shear_strain, dtype=float)
    return float(np.mean(np.asarray(values, dtype=float)[_window_mask(shear_strain, window)]))


def dilatancy_angle_deg(
    shear_displacement_m: np.ndarray,
    lid_rise_m: np.ndarray,
    shear_strain: np.ndarray,
    window: tuple[float, float] = (0.08, 0.10),
) -> float:
    """psi = atan(d_n / d_s) over the window (Eq. 3.8); positive when the sample dilates."""
    mask = _window_mask(np.asarray(shear_strain, dtype=float), window)
    ds = np.asarray(shear_displacement_m, dtype=float)[mask]
    dn = np.asarray(lid_rise_m, dtype=float)[mask]
    if np.ptp(ds) <= 0:
        raise ValueError("no shear displacement inside the window")
    slope = float(np.polyfit(ds, dn, 1)[0])
    return float(np.degrees(np.arctan(slope)))


@dataclass
class MohrCoulombFit:
    friction_angle_deg: float
    cohesion_pa: float
    r2: float


def mohr_coulomb_fit(normal_stress_pa, shear_stress_pa) -> MohrCoulombFit:
    """Least-squares line tau = c + sigma tan(phi) (Eqs. 3.1-3.2) and its R^2."""
    sigma = np.asarray(normal_stress_pa, dtype=float)
    tau = np.asarray(shear_stress_pa, dtype=float)
    if sigma.size < 2 or sigma.size != tau.size:
        raise ValueError("Mohr-Coulomb fit needs at least two (sigma, tau) pairs of equal length")
    if np.ptp(sigma) <= 0:
        raise ValueError("Mohr-Coulomb fit needs distinct normal stresses")
    slope, intercept = np.polyfit(sigma, tau, 1)
    predicted = intercept + slope * sigma
    ss_res = float(np.sum((tau - predicted) ** 2))
    ss_tot = float(np.sum((tau - tau.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else (1.0 if ss_res == 0 else 0.0)
    return MohrCoulombFit(float(np.degrees(np.arctan(slope))), float(intercept), float(r2))


@dataclass
class DstReduction:
    residual_shear_stress_pa: float
    residual_normal_stress_pa: float
    dilatancy_angle_deg: float
    smoothed_shear_stress_pa: np.ndarray
    smoothed_normal_stress_pa: np.ndarray


def reduce_dst(
    shear_displacement_m,
    shear_force_n,
    normal_force_n,
    lid_rise_m,
    container_area_m2: float,
    container_diameter_m: float,
    window: tuple[float, float] = (0.08, 0.10),
    span: int = 21,
) -> DstReduction:
    """One DST run: stresses = forces / A (Eqs. 3.6-3.7), strain = displacement / diameter."""
    ds = np.asarray(shear_displacement_m, dtype=float)
    strain = ds / container_diameter_m
    tau = moving_average(np.asarray(shear_force_n, dtype=float) / container_area_m2, span)
    sigma = moving_average(np.asarray(normal_force_n, dtype=float) / container_area_m2, span)
    return DstReduction(
        residual_shear_stress_pa=window_mean(strain, tau, window),
        residual_normal_stress_pa=window_mean(strain, sigma, window),
        dilatancy_angle_deg=dilatancy_angle_deg(ds, lid_rise_m, strain, window),
        smoothed_shear_stress_pa=tau,
        smoothed_normal_stress_pa=sigma,
    )
