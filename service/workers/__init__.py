"""Executors for queued jobs: local worker processes (default) and a Dask dispatcher."""
from service.workers.local import Worker, execute_claimed

__all__ = ["Worker", "execute_claimed"]
