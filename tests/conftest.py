import os

# Same thread count everywhere so that determinism checks compare like with like.
os.environ.setdefault("NUMBA_NUM_THREADS", "2")


import pytest  # noqa: E402


@pytest.fixture
def shear_only(monkeypatch):
    """A third evaluator backend, registered for the test only and for the shear box only: the
    stand-in's job function declared again under another name (the registry is a plain dict)."""
    from calibration.evaluator_registry import REGISTRY, Backend

    backend = Backend(name="shear-only", title="stand-in, shear box only", description="a test backend",
                      tests=("dst",), runner="calibration.standin_job:run_analytic")
    monkeypatch.setitem(REGISTRY, backend.name, backend)
    return backend
