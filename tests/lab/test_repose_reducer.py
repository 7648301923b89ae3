"""The angle-of-repose reducer on synthetic piles of known angle (analytic cones)."""
import math

import numpy as np
import pytest

from engine.lab.reducers import angle_of_repose


def cone_pile(alpha_deg, grain_d_m, apex_height_m, foot_height_m, runout_m, seed=0):
    """Grain tops on a cone of angle ``alpha_deg`` down to ``foot_height_m``, then one layer of grains
    (tops at one diameter) that ran out over the floor to ``runout_m``; grains at random places."""
    rng = np.random.default_rng(seed)
    r = 0.5 * grain_d_m
    tan_a = math.tan(math.radians(alpha_deg))
    foot_radius = (apex_height_m - foot_height_m) / tan_a
    n = int(runout_m**2 / r**2) * 12  # ~4 grain tops per grain cross-section area: a dense sample
    rho = runout_m * np.sqrt(rng.random(n))
    az = 2 * np.pi * rng.random(n)
    top = np.where(rho < foot_radius, apex_height_m - rho * tan_a, grain_d_m)
    pos = np.column_stack([rho * np.cos(az), rho * np.sin(az), top - r])
    return pos, np.full(n, r)


@pytest.mark.parametrize("alpha_deg, apex_grains", [(12.0, 3.2), (25.0, 3.6), (38.0, 4.5)])
def test_thin_pile_reads_the_flank_not_the_step_onto_the_runout(alpha_deg, apex_grains):
    # a pile a few grains high (the screening pile) whose foot stands 0.6 grain above the run-out
    # layer: that step is one bin wide whatever the slope, so it is not part of the flank. Bins of
    # 0.6 grain, as the procedure's (one sphere diameter of a four-sphere clump).
    d = 0.03
    pos, radii = cone_pile(alpha_deg, d, apex_height_m=apex_grains * d, foot_height_m=1.6 * d,
                           runout_m=apex_grains * d / math.tan(math.radians(alpha_deg)) + 4 * d)
    red = angle_of_repose(pos, radii, bin_width_m=0.6 * d, toe_height_m=1.5 * d)
    assert red.angle_of_repose_deg == pytest.approx(alpha_deg, abs=1.5)
    assert all(a == pytest.approx(alpha_deg, abs=4.0) for a in red.sector_angles_deg)


def test_tall_pile_leaves_out_the_rounded_cap():
    # a cone of 35 deg whose top third is rounded off (a parabolic cap tangent to the cone)
    d, alpha = 0.02, math.radians(35.0)
    rng = np.random.default_rng(1)
    apex, foot_radius = 0.3, 0.3 / math.tan(alpha)
    n = 60000
    rho = (foot_radius + 3 * d) * np.sqrt(rng.random(n))
    az = 2 * np.pi * rng.random(n)
    r_cap = 0.3 * foot_radius  # cap: h = h0 - rho^2 tan(a) / (2 r_cap), tangent to the cone at r_cap
    cone = apex - rho * math.tan(alpha)
    cap = apex - 0.5 * r_cap * math.tan(alpha) - rho**2 * math.tan(alpha) / (2 * r_cap)
    top = np.where(rho < r_cap, cap, np.maximum(cone, d))
    pos = np.column_stack([rho * np.cos(az), rho * np.sin(az), top - 0.5 * d])
    red = angle_of_repose(pos, np.full(n, 0.5 * d), bin_width_m=d, toe_height_m=1.5 * d)
    assert red.angle_of_repose_deg == pytest.approx(35.0, abs=1.0)


def test_flat_layer_has_no_flank():
    pos, radii = cone_pile(10.0, 0.03, apex_height_m=0.03, foot_height_m=0.03, runout_m=0.3)
    with pytest.raises(ValueError, match="flank"):
        angle_of_repose(pos, radii, bin_width_m=0.03, toe_height_m=0.045)


def test_flat_topped_pile_reads_its_flank():
    # a pile a few grains high keeps a flat top where the last of the column came down, and the top
    # has holes a grain deep: a frustum 3.6 grains high, 30 deg flank, flat top 5 grains across with
    # a ring one grain lower in it; neither the top nor its hole is part of the flank
    d, alpha = 0.03, math.radians(30.0)
    rng = np.random.default_rng(2)
    top_radius, height = 2.5 * d, 3.6 * d
    foot_radius = top_radius + (height - 1.6 * d) / math.tan(alpha)
    n = 40000
    rho = (foot_radius + 4 * d) * np.sqrt(rng.random(n))
    az = 2 * np.pi * rng.random(n)
    flank = height - (rho - top_radius) * math.tan(alpha)
    plateau = np.where((rho > 1.2 * d) & (rho < 1.8 * d), height - d, height)
    top = np.where(rho < top_radius, plateau, np.where(rho < foot_radius, flank, d))
    pos = np.column_stack([rho * np.cos(az), rho * np.sin(az), top - 0.5 * d])
    red = angle_of_repose(pos, np.full(n, 0.5 * d), bin_width_m=0.6 * d, toe_height_m=1.5 * d)
    assert red.angle_of_repose_deg == pytest.approx(30.0, abs=1.5)
