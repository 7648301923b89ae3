"""Session-scoped DEM runs shared by the slow lab tests (each is minutes of CPU: run once, side by side).

All at screening fidelity (Appendix A set-up, 20 mm spheres); where a trend test only needs a
fill and a CCT, the CCT runs the thesis's 4 cycles and E' averages cycles 2..4 as the thesis did (with
2 cycles, cycle 2 alone scattered enough to take the stiff/soft ratio from 1.7 down to 1.4: the
packing is still compacting).

Screening systems run on one thread (`serial_below_spheres`), so these runs are independent one-core jobs
(tests/lab/lab_runs.py names them). When collection ends, every run the selected tests need starts in a
pool of one process per core (spawned: a forked child would inherit numba's OpenMP state), and the tests
that use them are moved to the end of the session: the runs go on while the rest of the suite, much of
which waits on servers and browsers, runs beside them. Each fixture then waits for its own result. A run
wanted only when an earlier result asks for it (a sequential test's second stage) goes through the
`lab_run` fixture, which submits it to the same pool then.

Under pytest-xdist (the README's test command runs the suite on every core): the tests that use these runs are
one work unit (xdist_group LAB_GROUP), so one worker holds the pool, and they go first (tests/conftest.py) so that
the runs start at once; that worker starts the pool at its first such test (a worker that collects them does not
know whether it will run them) and waits for the runs while the other workers take the rest of the suite.
"""
from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import Future, ProcessPoolExecutor

import pytest

from lab_runs import GROUPS, RUNS, call

_FUTURES = pytest.StashKey[dict]()
_POOL = pytest.StashKey[ProcessPoolExecutor]()
_NEEDED = pytest.StashKey[set]()
# the xdist_group of the tests that use the pool (tests/conftest.py schedules a group given at collection first)
LAB_GROUP = "lab-dem-pool"


def _runs_of(item) -> list[str]:
    names = []
    for fixture in getattr(item, "fixturenames", ()):
        if fixture in RUNS:
            names.append(fixture)
        names.extend(GROUPS.get(fixture, ()))
    return names


def _xdist_worker(config) -> bool:
    return hasattr(config, "workerinput")


def pytest_itemcollected(item):
    # before any collection_modifyitems hook: xdist turns the mark into the item's work unit in its own.
    # `lab_run`'s users too: in another worker they would start a pool of their own
    if _runs_of(item) or "lab_run" in getattr(item, "fixturenames", ()):
        item.add_marker(pytest.mark.xdist_group(LAB_GROUP))


@pytest.hookimpl(trylast=True)  # after -m / -k have deselected
def pytest_collection_modifyitems(session, config, items):
    needed = {name for item in items for name in _runs_of(item)}
    config.stash[_FUTURES] = {}
    config.stash[_NEEDED] = needed
    if not needed or config.option.collectonly or _xdist_worker(config):
        return
    items.sort(key=lambda item: bool(_runs_of(item)))  # stable: the pool's users last, in their order
    _start_pool(config)


def _start_pool(config, submit_all: bool = True) -> ProcessPoolExecutor:
    needed = config.stash.get(_NEEDED, set())
    pool = ProcessPoolExecutor(max_workers=max(1, min(len(needed), os.cpu_count() or 1)),
                               mp_context=multiprocessing.get_context("spawn"))
    config.stash[_POOL] = pool
    # RUNS is longest first, so the last run to start is short
    config.stash[_FUTURES] = {name: pool.submit(call, name) for name in RUNS if name in needed and submit_all}
    return pool


def _pool(config) -> ProcessPoolExecutor | None:
    """The session's pool; in an xdist worker, started by the first test that needs a run. With --dist
    loadgroup every user of the pool is in this worker, so every run it needs starts then; with another
    distribution the users are spread over the workers, and each worker runs only what its tests ask for."""
    pool = config.stash.get(_POOL, None)
    if pool is None and _xdist_worker(config) and config.stash.get(_NEEDED, None):
        pool = _start_pool(config, submit_all=bool(config.getvalue("loadgroup")))
    return pool


def pytest_sessionfinish(session):
    pool = session.config.stash.get(_POOL, None)
    if pool is not None:
        pool.shutdown(wait=True, cancel_futures=True)


def _result(config, name: str):
    pool = _pool(config)
    futures = config.stash.get(_FUTURES, {})
    if pool is not None and name not in futures:
        futures[name] = pool.submit(call, name)
    future: Future | None = futures.get(name)
    # a run no collected test named (asked for through getfixturevalue) joins the pool, or runs here without one
    return call(name) if future is None else future.result()


@pytest.fixture(scope="session")
def lab_run(request):
    """``lab_run(names)`` -> their results, in order: runs not started yet go to the pool side by side
    (here, one after another, when the session started none)."""
    config = request.config

    def get(names: list[str]) -> list:
        pool = _pool(config)
        futures = config.stash.get(_FUTURES, {})
        if pool is not None:
            for name in names:
                if name not in futures:
                    futures[name] = pool.submit(call, name)
        return [_result(config, name) for name in names]
    return get


def _fixture(name: str):
    @pytest.fixture(scope="session", name=name)
    def _get(request):
        return _result(request.config, name)
    _get.__doc__ = f"The shared run {name!r} (lab_runs.RUNS)."
    return _get


def _group_fixture(group: str):
    @pytest.fixture(scope="session", name=group)
    def _get(request):
        return [_result(request.config, name) for name in GROUPS[group]]
    _get.__doc__ = f"The runs of lab_runs.GROUPS[{group!r}], in order."
    return _get


for _name in RUNS:
    globals()[_name] = _fixture(_name)
for _group in GROUPS:
    globals()[_group] = _group_fixture(_group)
