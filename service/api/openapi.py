"""The OpenAPI document says every status code an operation can answer, with one error schema.

Why: clients (and schemathesis in CI) read the document to know what can come back. FastAPI lists
only the success code and its own 422. The rules here add what our error handling emits, from
facts about each operation: a path parameter means a 404 when the row is missing and a 422 when it
is not an integer in range; any parameter or body means a 422, a body that is not text a 400; every write
may answer 401 (when a token is configured, always off loopback), and so may every read but health's and
this document's (``service.security.OPEN_API_PATHS``). Codes that depend on state (403 another user's object,
409 conflicts, 429 limits, 404 of a referenced row in a body) are declared on the routes themselves with
``errors(...)``.
"""
from __future__ import annotations

from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi
from pydantic import BaseModel

from service.api.links import add_links
from service.security import OPEN_API_PATHS, WRITE_METHODS


class ErrorItem(BaseModel):
    loc: list[str | int]
    msg: str
    type: str


class ErrorBody(BaseModel):
    """Every error: which field (``loc``), what is wrong (``msg``), and its kind (``type``)."""

    detail: list[ErrorItem]


_DESCRIPTIONS = {
    400: "the request body cannot be read (not UTF-8); malformed JSON is a 422",
    401: "missing or wrong bearer token (when tokens are configured: writes, and reads unless DEMCAL_OPEN_READS)",
    403: "another user's object: only its owner or an administrator may change it (when tokens are configured)",
    404: "a resource named in the path (or body) does not exist",
    409: "the resource's state does not allow this (field named)",
    422: "invalid input; each error names its field",
    429: "per-client limit of unfinished jobs reached",
    503: "storage unavailable",
}


def errors(*codes: int, **descriptions: str) -> dict[int | str, dict[str, Any]]:
    """``responses=`` entries for error codes, with the shared schema; ``c409="..."`` overrides a text."""
    return {code: {"model": ErrorBody, "description": descriptions.get(f"c{code}", _DESCRIPTIONS[code])}
            for code in codes}


def _error_response(schema_ref: str, code: int) -> dict[str, Any]:
    return {"description": _DESCRIPTIONS[code],
            "content": {"application/json": {"schema": {"$ref": schema_ref}}}}


def document_errors(app: FastAPI) -> None:
    """Replace ``app.openapi`` with one that adds the rule-based error responses (cached)."""

    def openapi() -> dict[str, Any]:
        if app.openapi_schema:
            return app.openapi_schema
        schema = get_openapi(title=app.title, version=app.version, description=app.description,
                             routes=app.routes)
        components = schema.setdefault("components", {}).setdefault("schemas", {})
        components.setdefault("ErrorItem", ErrorItem.model_json_schema())
        body = ErrorBody.model_json_schema(ref_template="#/components/schemas/{model}")
        body.pop("$defs", None)
        components.setdefault("ErrorBody", body)
        ref = "#/components/schemas/ErrorBody"
        for path, operations in schema.get("paths", {}).items():
            for method, operation in operations.items():
                responses = operation.setdefault("responses", {})
                params = operation.get("parameters", [])
                codes = []
                if any(p.get("in") == "path" for p in params):
                    codes += [404, 422]
                if params or "requestBody" in operation:
                    codes.append(422)
                if "requestBody" in operation:
                    codes.append(400)
                if method.upper() in WRITE_METHODS or path not in OPEN_API_PATHS:
                    codes.append(401)  # writes, and reads unless opened, need a token when tokens are configured
                for code in codes:
                    responses.setdefault(str(code), _error_response(ref, code))
        add_links(schema)
        app.openapi_schema = schema
        return schema

    app.openapi = openapi
