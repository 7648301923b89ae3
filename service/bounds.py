"""Bounds on a request's body, checked before a route (or the JSON decoder) sees it.

Why a raw ASGI middleware: a route's body is read in full by Starlette before validation, so a 100 MiB
body raised the server's memory by 1 GB, which it kept. Here ``Content-Length`` is compared with
``max_body_bytes`` first (413 without reading a byte), and a chunked body is read with a running count,
answered 413 as soon as it passes the cap. The body read is replayed to the application unchanged.

Why a nesting limit here and not in the models: a material whose ``direct_estimates`` nested 255-950
levels was stored, then every listing of materials answered 500 (the response serialiser's recursion
guard), for every client. Free-form JSON fields (``direct_estimates``, ``fixed_parameters``,
``options``) are ``Any``, so the one place that sees every one of them is the body. A JSON body nested
deeper than ``max_json_depth`` is a 422 naming the top-level field it nests under, before it is decoded
(a deep enough body would also exhaust the decoder's own recursion).

A NUL character anywhere in the path, the query or a JSON body's strings is a 422 too (``service.nul_text``:
PostgreSQL's text columns cannot hold it).
"""
from __future__ import annotations

import json

from service import nul_text
from service.config import Settings


def json_depth(body: bytes, limit: int) -> tuple[int, str | None]:
    """(depth, top-level key) at the first point ``body`` nests deeper than ``limit``; (0, None) if it never does.

    A scan of brackets outside strings, linear in the body and without recursion. The key is the last string
    seen at depth 1 before the container that goes too deep (the member it belongs to), None for a top-level list.
    """
    if body.count(b"{") + body.count(b"[") <= limit:  # cannot nest deeper than it opens: skip the byte loop
        return 0, None
    depth = 0
    in_string = escaped = False
    start = 0
    last_key: str | None = None
    for index, byte in enumerate(body):
        if in_string:
            if escaped:
                escaped = False
            elif byte == 0x5C:  # backslash
                escaped = True
            elif byte == 0x22:  # closing quote
                in_string = False
                if depth == 1:
                    last_key = body[start:index].decode("utf-8", "replace")
        elif byte == 0x22:
            in_string, start = True, index + 1
        elif byte in (0x7B, 0x5B):  # { [
            depth += 1
            if depth > limit:
                return depth, last_key
        elif byte in (0x7D, 0x5D):  # } ]
            depth -= 1
    return 0, None


def _is_json(headers: dict[bytes, bytes]) -> bool:
    kind = headers.get(b"content-type", b"").split(b";", 1)[0].strip().lower()
    return kind == b"application/json" or kind.endswith(b"+json")


class RequestBounds:
    """ASGI middleware: 413 over ``max_body_bytes`` (header first, then the stream), 422 over ``max_json_depth``."""

    def __init__(self, app, settings: Settings):
        self.app = app
        self.max_body = settings.max_body_bytes
        self.max_depth = settings.max_json_depth

    async def _reply(self, send, status: int, loc: list, msg: str, kind: str) -> None:
        body = json.dumps({"detail": [{"loc": loc, "msg": msg, "type": kind}]}).encode()
        await send({"type": "http.response.start", "status": status,
                    "headers": [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode()),
                                (b"connection", b"close")]})
        await send({"type": "http.response.body", "body": body})

    async def _too_large(self, send) -> None:
        await self._reply(send, 413, ["body"], f"the request body is over the limit of {self.max_body} bytes "
                          "(DEMCAL_MAX_BODY_BYTES)", "too_large")

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            return await self.app(scope, receive, send)
        if nul_text.NUL in scope.get("path", ""):
            return await self._reply(send, 422, ["path"], "NUL (U+0000) is not allowed in text", "value_error")
        if (name := nul_text.in_query(scope.get("query_string", b""))) is not None:
            return await self._reply(send, 422, ["query", name], "NUL (U+0000) is not allowed in text", "value_error")
        headers = dict(scope.get("headers") or ())
        length = headers.get(b"content-length")
        if length is not None:
            try:
                declared = int(length)
            except ValueError:
                return await self._reply(send, 400, ["header", "Content-Length"], "not a number", "bad_request")
            if declared > self.max_body:
                return await self._too_large(send)
        chunks: list[bytes] = []
        size = 0
        more = True
        while more:
            message = await receive()
            if message["type"] == "http.disconnect":
                return None
            chunk = message.get("body", b"")
            size += len(chunk)
            if size > self.max_body:
                return await self._too_large(send)
            chunks.append(chunk)
            more = message.get("more_body", False)
        body = b"".join(chunks)
        if body and _is_json(headers):
            depth, key = json_depth(body, self.max_depth)
            if depth:
                return await self._reply(
                    send, 422, ["body"] + ([key] if key is not None else []),
                    f"JSON nested deeper than {self.max_depth} levels (DEMCAL_MAX_JSON_DEPTH)", "value_error")
            if (where := nul_text.in_json(body)) is not None:
                return await self._reply(send, 422, ["body", *where], "NUL (U+0000) is not allowed in text",
                                         "value_error")
        replayed = False

        async def replay():
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()  # after the body: wait for the disconnect, as Starlette expects

        return await self.app(scope, replay, send)
