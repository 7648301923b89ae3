"""The browser UI: static HTML, vanilla JS (ES modules) and CSS, all served from this package.

Nothing is fetched from the web (no CDN): the pages talk only to this service's
own ``/api/v1``. ``mount(app)`` serves ``/`` (the single page), ``/static`` and ``/favicon.ico``.
"""
from __future__ import annotations

from pathlib import Path

from fastapi import FastAPI
from fastapi.responses import FileResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles

STATIC_DIR = Path(__file__).parent / "static"


def mount(app: FastAPI) -> None:
    app.mount("/static", StaticFiles(directory=STATIC_DIR), name="static")

    @app.get("/", include_in_schema=False)
    def index() -> FileResponse:
        return FileResponse(STATIC_DIR / "index.html", media_type="text/html")

    # browsers ask for /favicon.ico on every page that names no icon (the API docs too): the SVG icon
    # answers it, instead of a 404 in every page's log
    @app.get("/favicon.ico", include_in_schema=False)
    def favicon() -> FileResponse:
        return FileResponse(STATIC_DIR / "favicon.svg", media_type="image/svg+xml")

    @app.get("/ui", include_in_schema=False)
    def ui() -> RedirectResponse:
        return RedirectResponse("/")
