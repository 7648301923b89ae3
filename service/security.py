"""Bind address policy, bearer tokens for writes, and who a request is (its client identity).

Off loopback, anyone on the network could queue hour-long DEM runs, so every write
(POST/PUT/PATCH/DELETE) then needs ``Authorization: Bearer <token>``. Tokens can be named
(``DEMCAL_TOKENS=alice:<16+ chars>,bob:<16+ chars>``): the name is the client identity per-client limits
count against, so it cannot be forged by a header. Only on loopback (tests, a single user's
machine) may ``X-Client-Id`` choose the identity.

Resource limits (particles, simulated time, design size) are in ``service.limits``.
"""
from __future__ import annotations

import hmac
import ipaddress

from fastapi import FastAPI, Header, Request
from fastapi.responses import JSONResponse

from service.config import Settings
from service.errors import Unauthorized

WRITE_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})
DEFAULT_TOKEN_NAME = "token"
# A guessable token is no token: one character (or whitespace) was accepted. 16 characters of a random
# generator (e.g. ``python3 -c "import secrets; print(secrets.token_urlsafe(24))"``) are beyond guessing.
MIN_TOKEN_LENGTH = 16


def is_loopback(host: str | None) -> bool:
    """Only names that can mean nothing but this machine. "" (and 0.0.0.0, ::) mean every interface."""
    if host is None or host.strip() == "":
        return False
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host.strip("[]")).is_loopback
    except ValueError:
        return False


def token_names(settings: Settings) -> dict[str, str]:
    """token -> client name, from DEMCAL_TOKEN (named "token") and DEMCAL_TOKENS ("name:token,...").

    Refused with one line (at start: ``check_bind`` calls this before the socket opens) when a token is
    shorter than ``MIN_TOKEN_LENGTH`` or two users share one: a shared token silently merged two users
    into whichever name came last."""
    table: dict[str, str] = {}
    entries: list[tuple[str, str, str]] = []  # (variable, name, token)
    if settings.token is not None and settings.token != "":
        entries.append(("DEMCAL_TOKEN", DEFAULT_TOKEN_NAME, settings.token.strip()))
    for item in (settings.tokens or "").split(","):
        name, sep, token = item.strip().partition(":")
        if not item.strip():
            continue
        if not sep or not name.strip() or not token.strip():
            raise SystemExit(f"DEMCAL_TOKENS: {item.strip()!r} is not name:token")
        entries.append(("DEMCAL_TOKENS", name.strip(), token.strip()))
    for variable, name, token in entries:
        if len(token) < MIN_TOKEN_LENGTH:
            raise SystemExit(f"{variable}: the token of {name!r} has {len(token)} characters (after trimming "
                             f"spaces); at least {MIN_TOKEN_LENGTH} are needed")
        if token in table and table[token] != name:
            raise SystemExit(f"{variable}: {table[token]!r} and {name!r} have the same token; each user needs "
                             "their own")
        table[token] = name
    return table


def check_bind(settings: Settings) -> None:
    """Refuse to serve off loopback without a token (raised before the socket opens)."""
    if not is_loopback(settings.host) and not token_names(settings):
        where = repr(settings.host) if settings.host.strip() else '"" (every interface)'
        raise SystemExit(
            f"refusing to bind {where}: set DEMCAL_TOKEN or DEMCAL_TOKENS (write endpoints need a bearer token "
            "off loopback)")


def _match(table: dict[str, str], supplied: str) -> str | None:
    found = None
    for token, name in table.items():  # compare with every token: the time does not say which matched
        if hmac.compare_digest(supplied.encode(), token.encode()):
            found = name
    return found


def install_token_guard(app: FastAPI, settings: Settings) -> None:
    """Writes need a token whenever one is configured (always, off loopback); the token's name is
    stored as ``request.state.client_name``."""
    table = token_names(settings)
    if not table:
        return

    @app.middleware("http")
    async def _require_token(request: Request, call_next):
        header = request.headers.get("authorization", "")
        scheme, _, supplied = header.partition(" ")
        name = _match(table, supplied.strip()) if scheme.lower() == "bearer" else None
        request.state.client_name = name
        if request.method in WRITE_METHODS and name is None:
            err = Unauthorized("missing or wrong bearer token", ["header", "Authorization"])
            return JSONResponse({"detail": err.detail()}, status_code=401, headers={"WWW-Authenticate": "Bearer"})
        return await call_next(request)


def client_id(request: Request, x_client_id: str | None = Header(
        None, min_length=1, max_length=100,
        description="client identity for per-client limits; honoured from loopback peers only (off loopback "
                    "the identity is the bearer token's name)")) -> str:
    """Who per-client limits count against: the token's name; else, from a loopback peer, X-Client-Id;
    else the peer address. A remote peer cannot choose an identity by header."""
    name = getattr(request.state, "client_name", None)
    if name:
        return f"token:{name}"
    peer = request.client.host if request.client else None
    if x_client_id and (peer is None or is_loopback(peer)):
        return x_client_id
    return peer or "anonymous"
