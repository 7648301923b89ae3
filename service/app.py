"""The FastAPI application: settings in, routers under /api/v1, executors and ticks in the lifespan.

Start-up order matters: the schema is upgraded before anything touches it, the
bundled material is seeded, then the executors (local worker processes or a Dask
dispatcher) and the background ticker start; shutdown reverses it, handing
running jobs back to the queue.
"""
from __future__ import annotations

import importlib
import os
import threading
from contextlib import asynccontextmanager

from fastapi import FastAPI

from service.config import Settings, get_settings
from service.db import make_engine, make_session_factory
from service.api.openapi import document_errors
from service.browser_guard import BrowserGuard
from service.errors import install_error_handlers
from service.security import check_bind, install_token_guard, token_users

API_PREFIX = "/api/v1"
ROUTERS = ("jobs", "health", "rigs", "materials", "designs", "campaigns", "schedules", "effects", "evaluators", "tests",
           "export")


def _seed(session_factory) -> None:
    from service.materials import seed_bundled_materials
    from service.rigs import seed_bundled_rigs

    with session_factory() as session:
        seed_bundled_rigs(session)  # first: the bundled material names the thesis rig
        seed_bundled_materials(session)


def _start_executor(app: FastAPI, settings: Settings, session_factory) -> None:
    app.state.executor, app.state.worker_pool, app.state.dispatcher = "none", None, None
    if not settings.start_workers or settings.workers == 0:
        return
    if settings.dask_scheduler:
        from service.workers.dask_executor import DaskDispatcher

        dispatcher = DaskDispatcher(session_factory, settings, settings.dask_scheduler)
        thread = threading.Thread(target=dispatcher.run, name="demcal-dask-dispatcher", daemon=True)
        thread.start()
        app.state.executor, app.state.dispatcher, app.state.dispatcher_thread = "dask", dispatcher, thread
        return
    from service.workers.process import LocalWorkerPool

    pool = LocalWorkerPool(settings, settings.workers or os.cpu_count() or 1)
    pool.start()
    app.state.executor, app.state.worker_pool = "local", pool


def _stop_executor(app: FastAPI) -> None:
    if app.state.worker_pool is not None:
        app.state.worker_pool.stop()
    if app.state.dispatcher is not None:
        app.state.dispatcher.stop.set()
        app.state.dispatcher_thread.join(30)


def _background(app: FastAPI, settings: Settings, session_factory):
    from service.background import BackgroundTicker, default_ticks

    ticks = default_ticks(session_factory, settings)
    if app.state.worker_pool is not None:
        ticks.append(("worker-pool", app.state.worker_pool.supervise))
    ticker = BackgroundTicker(settings.tick_interval_s, ticks)
    ticker.start()
    return ticker


def create_app(settings: Settings | None = None) -> FastAPI:
    settings = settings or get_settings()
    check_bind(settings)

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        from service.migrate import upgrade

        upgrade(settings.database_url)
        if settings.seed_materials:
            _seed(app.state.session_factory)
        _start_executor(app, settings, app.state.session_factory)
        ticker = _background(app, settings, app.state.session_factory) if settings.start_background else None
        try:
            yield
        finally:
            if ticker is not None:
                ticker.stop()
            _stop_executor(app)
            app.state.engine.dispose()

    app = FastAPI(
        title="demcal", version="0.1.0", lifespan=lifespan,
        description="Calibration service for DEM models of bulk materials: materials and measurements, "
                    "queued DEM jobs, designs, calibration campaigns and schedules.",
        openapi_url=f"{API_PREFIX}/openapi.json", docs_url=None, redoc_url=None,  # served from vendored files: web.docs
    )
    app.state.settings = settings
    app.state.engine = make_engine(settings.database_url)
    app.state.session_factory = make_session_factory(app.state.engine, settings)
    app.state.executor, app.state.worker_pool, app.state.dispatcher = "none", None, None
    install_error_handlers(app)
    document_errors(app)
    install_token_guard(app, settings)
    app.state.tokens_configured = bool(token_users(settings))  # service.ownership: owners are checked
    from service.bounds import RequestBounds

    app.add_middleware(RequestBounds, settings=settings)  # outermost: a body is bounded before anything reads it
    for name in ROUTERS:
        app.include_router(importlib.import_module(f"service.api.{name}").router, prefix=API_PREFIX)
    from service import web

    from service.web.docs import mount_docs

    script_hashes = mount_docs(app, API_PREFIX)
    web.mount(app)  # at "/", after the API so /api/v1 routes win
    # added last, so outermost: Host, Origin and Content-Type are checked before the token guard and
    # every route, and every response (errors too) gets the security headers
    app.add_middleware(BrowserGuard, settings=settings, script_hashes=script_hashes)
    return app
