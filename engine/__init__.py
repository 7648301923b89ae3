"""demcal's numba DEM engine."""
import os

from numba.core import config as _numba_config

__version__ = "0.1.0"

if "NUMBA_THREADING_LAYER" not in os.environ and "NUMBA_THREADING_LAYER_PRIORITY" not in os.environ:
    # numba's default prefers TBB, whose layer grew ~30 KB per parallel neighbour rebuild here (a run of
    # 100k steps reached 1 GB and crawled); OpenMP and the workqueue do not. Must be set before the first
    # parallel kernel launches, hence here. An explicit NUMBA_THREADING_LAYER still wins.
    _numba_config.THREADING_LAYER_PRIORITY = ["omp", "workqueue", "tbb"]
