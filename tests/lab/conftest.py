"""Session-scoped DEM runs shared by the slow lab tests (each is minutes of CPU: run once, side by side).

All at screening fidelity (Appendix A set-up, 20 mm spheres); where a trend test only needs a
fill and a CCT, the CCT runs the thesis's 4 cycles and E' averages cycles 2..4 as the thesis did (with
2 cycles, cycle 2 alone scattered enough to take the stiff/soft ratio from 1.7 down to 1.4: the
packing is still compacting).

Screening systems run on one thread (`serial_below_spheres`), so these runs are independent one-core jobs:
the first fixture asked for starts every run the collected tests need in a pool of one process per core
(spawned: a forked child would inherit numba's OpenMP state), and each fixture waits for its own. Run one
after the other they cost the suite's wall clock about twice as much on two cores.
"""
from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor

import pytest

from lab_runs import RUNS, call


def pytest_collection_modifyitems(session, config, items):
    """Remember which runs the collected tests use, so the pool starts those and no others."""
    needed = set()
    for item in items:
        needed.update(name for name in getattr(item, "fixturenames", ()) if name in RUNS)
    config.stash[_NEEDED] = needed


_NEEDED = pytest.StashKey[set]()


@pytest.fixture(scope="session")
def lab_runs(request) -> dict[str, Future]:
    needed = [name for name in RUNS if name in request.config.stash.get(_NEEDED, set(RUNS))]
    pool = ProcessPoolExecutor(max_workers=max(1, min(len(needed), os.cpu_count() or 1)),
                               mp_context=multiprocessing.get_context("spawn"))
    futures = {name: pool.submit(call, name) for name in needed}
    yield futures
    pool.shutdown(wait=True, cancel_futures=True)


def _fixture(name: str):
    @pytest.fixture(scope="session", name=name)
    def _get(lab_runs):
        if name not in lab_runs:  # asked for by a test the collection did not see (e.g. getfixturevalue)
            return call(name)
        return lab_runs[name].result()
    _get.__doc__ = f"The shared run {name!r} (see RUNS)."
    return _get


for _name in RUNS:
    globals()[_name] = _fixture(_name)
