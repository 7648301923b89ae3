"""Virtual laboratory (filled in by the lab work): procedures, reducers, battery, run_job."""
