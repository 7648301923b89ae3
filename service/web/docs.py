"""The API's interactive docs (Swagger UI and ReDoc) from the service's own vendored files.

Why: FastAPI's default pages load Swagger UI and ReDoc from a CDN, so ``/api/v1/docs`` is a blank
page on a machine without internet (the usual case beside a lab rig) while the README sends users
there. The same FastAPI page builders are pointed at ``/static/vendor`` (see its README.md for
the pinned versions and licences); the Swagger validator badge (a call to validator.swagger.io)
and ReDoc's Google fonts are switched off for the same reason.

The pages are built once, at mount: Swagger UI's start-up is an inline ``<script>``, which the
Content-Security-Policy (``service.browser_guard``) admits by its SHA-256 only, so the hash must be
of exactly the bytes served.
"""
from __future__ import annotations

import base64
import hashlib
import re

from fastapi import FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import HTMLResponse

SWAGGER = "/static/vendor/swagger-ui-dist-5.35.0"
REDOC = "/static/vendor/redoc-2.5.4"
_INLINE_SCRIPT = re.compile(r"<script>(.*?)</script>", re.DOTALL)


def inline_script_hashes(html: str) -> tuple[str, ...]:
    """CSP source expressions (``sha256-...``) of the page's inline scripts, as browsers hash them."""
    return tuple("sha256-" + base64.b64encode(hashlib.sha256(body.encode()).digest()).decode()
                 for body in _INLINE_SCRIPT.findall(html))


def mount_docs(app: FastAPI, api_prefix: str) -> tuple[str, ...]:
    """``{api_prefix}/docs`` (Swagger UI) and ``{api_prefix}/redoc``; the app must be built with
    ``docs_url=None, redoc_url=None`` so that FastAPI's CDN pages are not registered first.
    Returns the CSP hashes of the pages' inline scripts."""
    openapi_url = app.openapi_url
    title = f"{app.title} API"
    swagger_html = get_swagger_ui_html(openapi_url=openapi_url, title=title,
                                       swagger_js_url=f"{SWAGGER}/swagger-ui-bundle.js",
                                       swagger_css_url=f"{SWAGGER}/swagger-ui.css",
                                       swagger_favicon_url=f"{SWAGGER}/favicon-32x32.png",
                                       swagger_ui_parameters={"validatorUrl": None}).body.decode()
    redoc_html = get_redoc_html(openapi_url=openapi_url, title=title, redoc_js_url=f"{REDOC}/redoc.standalone.js",
                                redoc_favicon_url=f"{SWAGGER}/favicon-32x32.png",
                                with_google_fonts=False).body.decode()

    @app.get(f"{api_prefix}/docs", include_in_schema=False)
    def swagger_ui() -> HTMLResponse:
        return HTMLResponse(swagger_html)

    @app.get(f"{api_prefix}/redoc", include_in_schema=False)
    def redoc() -> HTMLResponse:
        return HTMLResponse(redoc_html)

    return inline_script_hashes(swagger_html) + inline_script_hashes(redoc_html)
