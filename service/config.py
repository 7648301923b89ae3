"""One settings object for the service, read from ``DEMCAL_*`` environment variables.

Why one object: the API, the workers (separate processes), the Dask dispatcher and
the background thread must agree on the database URL, lease timings and limits; a
worker process started by ``demcal serve`` inherits them through the environment.
"""
from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path

from pydantic import BaseModel, ConfigDict, Field

DEFAULT_DATA_DIR = Path("demcal-data")


def default_database_url() -> str:
    """SQLite file under ``./demcal-data`` so ``demcal serve`` works on a fresh machine."""
    return f"sqlite:///{(DEFAULT_DATA_DIR / 'demcal.db').as_posix()}"


class Settings(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)

    database_url: str = Field(default_factory=default_database_url)
    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)
    workers: int | None = Field(None, ge=0, description="local worker processes; None = one per core")
    threads_per_job: int | None = Field(
        None, ge=1, description="numba threads of each local worker's jobs; None = cores // workers (at least 1): "
        "jobs side by side on one thread each give the most batteries per hour (bench/battery_threads.py)")
    token: str | None = Field(None, description="the operator's bearer token (user 'token', an administrator): writes "
                                                "need it (a token is required off loopback), reads too unless "
                                                "open_reads; at least 16 characters (service.security.MIN_TOKEN_LENGTH)")
    tokens: str | None = Field(
        None, description="named bearer tokens 'alice:s3cret-0123456789ab:admin,bob:0ther-0123456789ab' (DEMCAL_TOKENS): "
                          "the name is the user who owns what the request makes and the client identity per-client "
                          "limits count against; ':admin' makes the user an administrator, who may change anyone's "
                          "jobs, materials, campaigns and schedules (others get 403). Each token at least 16 "
                          "characters, without ':', no two users sharing one. DEMCAL_TOKEN's user 'token' is an "
                          "administrator")
    open_reads: bool = Field(
        False, description="with tokens configured, let GET requests of the API through without a token "
                           "(DEMCAL_OPEN_READS=1); by default they need one, except /api/v1/health, the OpenAPI "
                           "document and the page's own files")
    trusted_proxies: str | None = Field(
        None, description="reverse proxies whose X-Forwarded-For and X-Client-Id are believed, comma-separated "
                          "addresses or networks (DEMCAL_TRUSTED_PROXIES=127.0.0.1,10.0.0.0/8); from any other "
                          "peer, loopback included, both headers are ignored (a forged one chose the identity "
                          "per-client limits count against)")
    allowed_hosts: str | None = Field(
        None, description="extra Host names the service answers to, comma-separated (DEMCAL_ALLOWED_HOSTS); "
                          "loopback names and DEMCAL_HOST are always allowed, any other Host gets 400 (a web "
                          "page that rebinds its DNS name to this machine is refused); '*' allows any")
    lease_s: float = Field(30.0, gt=0, description="a claimed job is lost unless heartbeated within this")
    heartbeat_s: float = Field(5.0, gt=0)
    poll_interval_s: float = Field(0.5, gt=0, description="idle worker wait between claim attempts")
    max_attempts: int = Field(3, ge=1, description="claims per job before a lost lease fails it")
    tick_interval_s: float = Field(2.0, gt=0, description="campaign runner / scheduler period")
    dask_scheduler: str | None = None
    dask_connect_timeout_s: float = Field(
        10.0, gt=0, description="how long the Dask client tries to (re)connect before the dispatcher drops it "
                                "and starts over (it keeps trying, reporting unhealthy meanwhile)")
    max_particles: int = Field(200_000, ge=1)
    max_simulated_time_s: float = Field(3600.0, gt=0)
    max_queued_jobs_per_client: int = Field(10_000, ge=1)
    max_design_runs: int = Field(512, ge=1, description="runs of one design (campaign or preview)")
    max_body_bytes: int = Field(
        16 * 1024 * 1024, ge=1024, description="largest request body (default 16 MiB); larger is a 413, refused on "
        "Content-Length before it is read, or as soon as a chunked body passes it (service.bounds)")
    max_json_depth: int = Field(
        32, ge=4, le=200, description="deepest nesting of a JSON body (default 32); deeper is a 422 naming the "
        "field: free-form JSON nested ~255 levels was stored and then broke every listing (service.bounds)")
    start_workers: bool = True
    start_background: bool = True
    seed_materials: bool = True


ENV_PREFIX = "DEMCAL_"


def settings_from_env(environ: dict[str, str] | None = None, **overrides) -> Settings:
    """Build Settings from DEMCAL_<FIELD> variables, then explicit overrides (CLI flags)."""
    env = os.environ if environ is None else environ
    values: dict[str, object] = {}
    for name in Settings.model_fields:
        raw = env.get(ENV_PREFIX + name.upper())
        if raw is not None and raw != "":
            values[name] = raw
    values.update({k: v for k, v in overrides.items() if v is not None})
    return Settings(**values)


@lru_cache(maxsize=1)
def get_settings() -> Settings:
    return settings_from_env()


__all__ = ["Settings", "settings_from_env", "get_settings", "default_database_url"]
