"""Virtual laboratory (filled in by the lab work): procedures, reducers, battery, run_job."""
from engine.lab.result import Cancelled  # noqa: F401  (contract: engine.lab.Cancelled)
