"""The API's interactive docs (Swagger UI and ReDoc) from the service's own vendored files.

Why: FastAPI's default pages load Swagger UI and ReDoc from a CDN, so ``/api/v1/docs`` is a blank
page on a machine without internet (the usual case beside a lab rig) while the README sends users
there. The same FastAPI page builders are pointed at ``/static/vendor`` (see its README.md for
the pinned versions and licences); the Swagger validator badge (a call to validator.swagger.io)
and ReDoc's Google fonts are switched off for the same reason.
"""
from __future__ import annotations

from fastapi import FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import HTMLResponse

SWAGGER = "/static/vendor/swagger-ui-dist-5.35.0"
REDOC = "/static/vendor/redoc-2.5.4"


def mount_docs(app: FastAPI, api_prefix: str) -> None:
    """``{api_prefix}/docs`` (Swagger UI) and ``{api_prefix}/redoc``; the app must be built with
    ``docs_url=None, redoc_url=None`` so that FastAPI's CDN pages are not registered first."""
    openapi_url = app.openapi_url
    title = f"{app.title} API"

    @app.get(f"{api_prefix}/docs", include_in_schema=False)
    def swagger_ui() -> HTMLResponse:
        return get_swagger_ui_html(openapi_url=openapi_url, title=title,
                                   swagger_js_url=f"{SWAGGER}/swagger-ui-bundle.js",
                                   swagger_css_url=f"{SWAGGER}/swagger-ui.css",
                                   swagger_favicon_url=f"{SWAGGER}/favicon-32x32.png",
                                   swagger_ui_parameters={"validatorUrl": None})

    @app.get(f"{api_prefix}/redoc", include_in_schema=False)
    def redoc() -> HTMLResponse:
        return get_redoc_html(openapi_url=openapi_url, title=title, redoc_js_url=f"{REDOC}/redoc.standalone.js",
                              redoc_favicon_url=f"{SWAGGER}/favicon-32x32.png", with_google_fonts=False)
