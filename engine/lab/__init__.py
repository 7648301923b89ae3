"""Virtual laboratory: the thesis's bulk tests as engine procedures, pure reducers, battery, ``run_job``.

``run_job(spec, progress=None, should_cancel=None) -> LabResult``; ``Cancelled`` is raised when
``should_cancel()`` answers True. See docs/lab.md.
"""
from engine.lab.result import Cancelled  # noqa: F401  (contract: engine.lab.Cancelled)


def run_job(spec, progress=None, should_cancel=None):
    """Run one virtual-lab test or battery (``engine.lab.battery.run_job``)."""
    from engine.lab.battery import run_job as _run_job

    return _run_job(spec, progress=progress, should_cancel=should_cancel)


__all__ = ["Cancelled", "run_job"]
