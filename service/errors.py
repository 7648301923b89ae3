"""API errors that name the offending field, rendered like FastAPI's own 422 body.

Every error, ours or FastAPI's validation error, has the shape
``{"detail": [{"loc": [...], "msg": ..., "type": ...}]}`` so a client has one
place to look for which field was wrong.
"""
from __future__ import annotations

import logging
import re

from fastapi import FastAPI, Request
from fastapi.encoders import jsonable_encoder
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import ValidationError
from starlette.exceptions import HTTPException as StarletteHTTPException

from calibration.errors import SettingsError

log = logging.getLogger(__name__)


class ApiError(Exception):
    status_code = 400
    error_type = "bad_request"

    def __init__(self, status_code: int, message: str, field: str | list | None = None):
        super().__init__(message)
        self.status_code = status_code
        self.message = message
        self.field = field

    def loc(self) -> list:
        """``"parameters.friction_pp"`` -> ``["body", "parameters", "friction_pp"]``; lists pass through."""
        if self.field is None:
            return []
        if isinstance(self.field, (list, tuple)):
            return list(self.field)
        parts = str(self.field).split(".")
        return parts if parts[0] in ("body", "path", "query", "header") else ["body", *parts]

    def detail(self) -> list[dict]:
        return [{"loc": self.loc(), "msg": self.message, "type": self.error_type}]


class NotFound(ApiError):
    status_code = 404

    def __init__(self, message: str, field: str | list | None = None):
        super().__init__(404, message, field)
    error_type = "not_found"


class Conflict(ApiError):
    status_code = 409

    def __init__(self, message: str, field: str | list | None = None):
        super().__init__(409, message, field)
    error_type = "conflict"


class Invalid(ApiError):
    status_code = 422

    def __init__(self, message: str, field: str | list | None = None):
        super().__init__(422, message, field)
    error_type = "value_error"


class TooMany(ApiError):
    status_code = 429

    def __init__(self, message: str, field: str | list | None = None):
        super().__init__(429, message, field)
    error_type = "too_many"


class Unauthorized(ApiError):
    status_code = 401

    def __init__(self, message: str, field: str | list | None = None):
        super().__init__(401, message, field)
    error_type = "unauthorized"


class Forbidden(ApiError):
    """The request is authenticated but may not change this object (another user's; ``service.ownership``)."""

    status_code = 403

    def __init__(self, message: str, field: str | list | None = None):
        super().__init__(403, message, field)
    error_type = "forbidden"


def from_settings_error(exc: SettingsError) -> ApiError:
    """The loop's complaint about a setting (``calibration.errors.SettingsError``) as the API's error:
    a 409 when it clashes with the campaign's state, else a 422, naming the field either way."""
    return (Conflict if exc.conflict else Invalid)(exc.message, exc.field)


def _validation_detail(exc: ValidationError, prefix: tuple = ("body",)) -> list[dict]:
    return [
        {"loc": [*prefix, *err.get("loc", ())], "msg": err.get("msg", ""), "type": err.get("type", "value_error")}
        for err in exc.errors(include_url=False)
    ]


_LEADING_FIELD = re.compile(r"^(?:Value error, )?([a-z_][a-z0-9_]*)(?:\[(\d+)\])?[ :]")


def _field_of_model_error(loc: list, msg: str, body) -> list:
    """A cross-field rule (a model validator) is reported by pydantic at the whole body; its message
    starts with the field it refuses ("diagnose_always needs diagnose", "constraints[0]: ..."), so
    the error points there when the body has that field: a client, or the web form, can mark it."""
    if loc != ["body"] or not isinstance(body, dict):
        return loc
    match = _LEADING_FIELD.match(msg)
    if match is None or match.group(1) not in body:
        return loc
    return ["body", match.group(1)] + ([int(match.group(2))] if match.group(2) is not None else [])


def allowed_methods(request: Request) -> list[str]:
    """Every method the API documents for this path. Starlette's 405 lists only the first matching
    route's methods, so ``GET /materials`` and ``POST /materials`` (two routes) each hid the other; the
    OpenAPI document is the contract the Allow header must agree with."""
    import re

    path = request.url.path
    paths = request.app.openapi().get("paths", {})
    if path in paths:  # a fixed path (/materials/quantities) is not also /materials/{material_id}
        return sorted(m.upper() for m in paths[path])
    methods: set[str] = set()
    for template, operations in paths.items():
        pattern = "^" + re.sub(r"\\\{[^/]+?\\\}", "[^/]+", re.escape(template)) + "$"
        if re.match(pattern, path):
            methods |= {m.upper() for m in operations}
    return sorted(methods)


def _wrong_method_on_fixed_path(request: Request) -> bool:
    """A method the API does not document for a fixed path, which a parameterised sibling route took
    (DELETE /materials/quantities reached DELETE /materials/{material_id} and answered 422 on the id)."""
    operations = request.app.openapi().get("paths", {}).get(request.url.path)
    return operations is not None and request.method.lower() not in operations


def install_error_handlers(app: FastAPI) -> None:
    @app.exception_handler(ApiError)
    async def _api_error(_request: Request, exc: ApiError):
        headers = {"WWW-Authenticate": "Bearer"} if exc.status_code == 401 else None
        return JSONResponse({"detail": exc.detail()}, status_code=exc.status_code, headers=headers)

    @app.exception_handler(SettingsError)
    async def _settings_error(request: Request, exc: SettingsError):
        return await _api_error(request, from_settings_error(exc))

    @app.exception_handler(RequestValidationError)
    async def _request_validation(request: Request, exc: RequestValidationError):
        if _wrong_method_on_fixed_path(request):
            return JSONResponse({"detail": [{"loc": [], "msg": "Method Not Allowed", "type": "http_error"}]},
                                status_code=405, headers={"Allow": ", ".join(allowed_methods(request))})
        detail = [
            {"loc": _field_of_model_error(list(err.get("loc", ())), err.get("msg", ""), getattr(exc, "body", None)),
             "msg": err.get("msg", ""), "type": err.get("type", "value_error")}
            for err in exc.errors()
        ]
        return JSONResponse({"detail": jsonable_encoder(detail)}, status_code=422)

    @app.exception_handler(ValidationError)
    async def _model_validation(_request: Request, exc: ValidationError):
        # pydantic errors raised by service code (e.g. a stored template re-validated).
        return JSONResponse({"detail": jsonable_encoder(_validation_detail(exc))}, status_code=422)

    @app.exception_handler(StarletteHTTPException)
    async def _http_error(request: Request, exc: StarletteHTTPException):
        detail = exc.detail if isinstance(exc.detail, list) else [
            {"loc": [], "msg": str(exc.detail), "type": "http_error"}]
        headers = dict(getattr(exc, "headers", None) or {})
        if exc.status_code == 405:
            headers["Allow"] = ", ".join(allowed_methods(request))
        return JSONResponse({"detail": detail}, status_code=exc.status_code, headers=headers or None)

    @app.exception_handler(Exception)
    async def _unexpected(_request: Request, exc: Exception):
        log.exception("unhandled error", exc_info=exc)
        return JSONResponse({"detail": [{"loc": [], "msg": "internal server error", "type": "internal"}]},
                            status_code=500)
