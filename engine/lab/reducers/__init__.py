"""Pure reducers: laboratory or simulated curves in, bulk properties out.

They know nothing of DEM, so they are tested on synthetic curves with known answers and
applied unchanged to laboratory data that users upload.
"""
from engine.lab.reducers.packing import PackingState, bulk_properties
from engine.lab.reducers.cct import CctReduction, reduce_cct, split_cycles
from engine.lab.reducers.dst import (
    DstReduction,
    MohrCoulombFit,
    dilatancy_angle_deg,
    mohr_coulomb_fit,
    moving_average,
    reduce_dst,
    window_mean,
)
from engine.lab.reducers.repose import ReposeReduction, angle_of_repose
from engine.lab.reducers.anchor import AnchorReduction, reduce_anchor

__all__ = [
    "PackingState", "bulk_properties",
    "CctReduction", "reduce_cct", "split_cycles",
    "DstReduction", "MohrCoulombFit", "dilatancy_angle_deg", "mohr_coulomb_fit",
    "moving_average", "reduce_dst", "window_mean",
    "ReposeReduction", "angle_of_repose",
    "AnchorReduction", "reduce_anchor",
]
