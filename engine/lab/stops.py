"""The stop rules of the procedures: how long each phase may run before it gives up, in SI.

Why one module: the procedures obey these limits and the cost model (``engine.lab.cost``) counts
them, so a ceiling of the simulated time cannot drift from what the procedures actually allow.
"""
from __future__ import annotations

# Rainfall (shear-box fill, angle-of-repose bucket, anchor bin): settling stops at this time at the latest.
RAIN_SETTLE_MAX_S = 6.0
# After levelling (deleting the bodies above the level), the packing settles again for at most this long.
LEVEL_SETTLE_MAX_S = 2.0
# The angle-of-repose pile comes to rest on the floor for at most this long after the bucket is lifted.
PILE_REST_MAX_S = 5.0
# The direct shear test holds each normal stress with the servo for at most this long before shearing (and the
# CCT's unload-reload each of its stresses before unloading).
DST_STABILISE_MAX_S = 0.5
# The CCT's small unloading of an unload-reload (options.cct_unload_reload_stresses_pa) runs at most this long.
UNLOAD_RELOAD_MAX_S = 1.0
# The angle-of-repose bucket is lifted at most this many bucket heights (a plug wedged in it rides up).
AOR_MAX_LIFT_BUCKET_HEIGHTS = 3.0
# A lid stroke (CCT cycle half, DST reload) travels at most this fraction of the packing height.
LID_MAX_TRAVEL_FRACTION = 0.5
