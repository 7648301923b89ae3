import os

# Same thread count everywhere so that determinism checks compare like with like.
os.environ.setdefault("NUMBA_NUM_THREADS", "2")


import pytest  # noqa: E402

@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """Under pytest-xdist (the README's test command: ``-n auto --dist loadgroup --no-loadscope-reorder``) a
    test file is one unit of work, so its module- and class-scoped fixtures (a Janssen column, a live server)
    are built once. A group a conftest gave its tests while collecting them (the lab's pool of DEM runs,
    tests/lab/conftest.py) stays one unit and goes out first: its runs are most of the suite's CPU and start
    when its first test asks. Then the files that hold a slow test, then the rest, so no long file starts last.
    Without xdist nothing changes here."""
    if not hasattr(config, "workerinput"):
        return
    unit_of, grouped = {}, set()
    for item in items:
        if item.get_closest_marker("xdist_group") is None:
            item.add_marker(pytest.mark.xdist_group(item.nodeid.split("::", 1)[0]))
        else:
            grouped.add(item)
        unit_of[item] = next(item.iter_markers("xdist_group")).args[0]
    slow_units = {unit_of[item] for item in items if item.get_closest_marker("slow") is not None}
    items.sort(key=lambda item: 0 if item in grouped else 1 if unit_of[item] in slow_units else 2)


@pytest.fixture
def shear_only(monkeypatch):
    """A third evaluator backend, registered for the test only and for the shear box only: the
    stand-in's job function declared again under another name (the registry is a plain dict)."""
    from calibration.evaluator_registry import REGISTRY, Backend

    backend = Backend(name="shear-only", title="stand-in, shear box only", description="a test backend",
                      tests=("dst",), runner="calibration.standin_job:run_analytic")
    monkeypatch.setitem(REGISTRY, backend.name, backend)
    return backend
