"""Bind address policy, bearer tokens, roles, and who a request is (its user and its client identity).

Off loopback, anyone on the network could queue hour-long DEM runs, so every write
(POST/PUT/PATCH/DELETE) then needs ``Authorization: Bearer <token>``. Tokens can be named
(``DEMCAL_TOKENS=alice:<16+ chars>:admin,bob:<16+ chars>``): the name is the user who owns what the
request makes (``service.ownership``) and the client identity per-client limits count against, so it
cannot be forged by a header; ``:admin`` after a token makes its user an administrator, who may change
anyone's objects. The single ``DEMCAL_TOKEN`` (user ``token``) is an administrator: it is the operator's.

Whenever a token is configured, reads need one too (job specs, token names, idempotency keys and worker
host:pid are a team's business, not the network's), except the page's own files, ``/api/v1/health`` and the
OpenAPI document and its docs pages; ``DEMCAL_OPEN_READS=1`` opens every read.

``X-Forwarded-For`` and ``X-Client-Id`` are honoured only from a peer in ``DEMCAL_TRUSTED_PROXIES``
(addresses or networks): from anyone else they are forgeries, which let one client queue past its limit
under as many identities as it liked. Nothing is trusted by default, loopback included.

Resource limits (particles, simulated time, design size) are in ``service.limits``.
"""
from __future__ import annotations

import hmac
import ipaddress
from dataclasses import dataclass

from fastapi import FastAPI, Header, Request
from fastapi.responses import JSONResponse

from service.config import Settings
from service.errors import Unauthorized
from service.models.base import IDENTITY_LENGTH

WRITE_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})
DEFAULT_TOKEN_NAME = "token"
ADMIN_ROLE = "admin"
ROLES = frozenset({ADMIN_ROLE})
# A guessable token is no token: one character (or whitespace) was accepted. 16 characters of a random
# generator (e.g. ``python3 -c "import secrets; print(secrets.token_urlsafe(24))"``) are beyond guessing.
MIN_TOKEN_LENGTH = 16
# A request with a token counts against ``token:<name>``, stored in the identity columns: a longer name
# would overflow them on PostgreSQL (SQLite does not enforce VARCHAR widths, so tests there never saw it).
TOKEN_CLIENT_PREFIX = "token:"
MAX_USER_NAME_LENGTH = IDENTITY_LENGTH - len(TOKEN_CLIENT_PREFIX)
# Paths under the API any reader may fetch although tokens are configured: health (counts only, for load
# balancers and ``wait_healthy``), the OpenAPI document (the page's forms read their bounds there) and the
# API docs that show it (service.web.docs). None of them holds anyone's data.
OPEN_API_PATHS = ("/api/v1/health", "/api/v1/openapi.json", "/api/v1/docs", "/api/v1/redoc")
API_PREFIX = "/api/v1"


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


@dataclass(frozen=True)
class TokenUser:
    name: str
    admin: bool


def _entries(settings: Settings) -> list[tuple[str, str, str, bool]]:
    """(variable, name, token, admin) of every configured token. ``name:token[:admin]``; a token cannot
    contain ``:`` (urlsafe tokens never do), so the role cannot be mistaken for a token's tail."""
    entries: list[tuple[str, str, str, bool]] = []
    if settings.token is not None and settings.token != "":
        entries.append(("DEMCAL_TOKEN", DEFAULT_TOKEN_NAME, settings.token.strip(), True))
    for item in (settings.tokens or "").split(","):
        if not item.strip():
            continue
        parts = [part.strip() for part in item.strip().split(":")]
        role = parts.pop() if len(parts) == 3 else None
        if len(parts) != 2 or not parts[0] or not parts[1] or (role is not None and role not in ROLES):
            raise SystemExit(f"DEMCAL_TOKENS: {item.strip()!r} is not name:token or name:token:admin "
                             "(a token cannot contain ':')")
        entries.append(("DEMCAL_TOKENS", parts[0], parts[1], role == ADMIN_ROLE))
    return entries


def token_users(settings: Settings) -> dict[str, TokenUser]:
    """token -> its user (name and role), from DEMCAL_TOKEN (user "token", an administrator) and
    DEMCAL_TOKENS ("name:token[:admin],...").

    Refused with one line (at start: ``check_bind`` calls this before the socket opens) when a token is
    shorter than ``MIN_TOKEN_LENGTH``, a user name longer than ``MAX_USER_NAME_LENGTH`` or two users share one: a shared token silently merged two users
    into whichever name came last."""
    table: dict[str, TokenUser] = {}
    for variable, name, token, admin in _entries(settings):
        if len(name) > MAX_USER_NAME_LENGTH:
            raise SystemExit(f"{variable}: the user name {name[:20]!r}... has {len(name)} characters; at most "
                             f"{MAX_USER_NAME_LENGTH} are stored")
        if len(token) < MIN_TOKEN_LENGTH:
            raise SystemExit(f"{variable}: the token of {name!r} has {len(token)} characters (after trimming "
                             f"spaces); at least {MIN_TOKEN_LENGTH} are needed")
        if token in table and table[token].name != name:
            raise SystemExit(f"{variable}: {table[token].name!r} and {name!r} have the same token; each user "
                             "needs their own")
        table[token] = TokenUser(name, admin or (token in table and table[token].admin))
    return table


def token_names(settings: Settings) -> dict[str, str]:
    """token -> user name (``token_users`` without the roles)."""
    return {token: user.name for token, user in token_users(settings).items()}


def check_bind(settings: Settings) -> None:
    """Refuse to serve off loopback without a token (raised before the socket opens); refuse a trusted
    proxy list that is not addresses or networks."""
    trusted_proxies(settings)
    if not is_loopback(settings.host) and not token_users(settings):
        where = repr(settings.host) if settings.host.strip() else '"" (every interface)'
        raise SystemExit(
            f"refusing to bind {where}: set DEMCAL_TOKEN or DEMCAL_TOKENS (write endpoints need a bearer token "
            "off loopback)")


def _match(table: dict[str, TokenUser], supplied: str) -> TokenUser | None:
    found = None
    for token, user in table.items():  # compare with every token: the time does not say which matched
        if hmac.compare_digest(supplied.encode(), token.encode()):
            found = user
    return found


def read_is_open(path: str, settings: Settings) -> bool:
    """Whether a read (GET, HEAD, OPTIONS) of ``path`` needs no token although tokens are configured:
    the page and its files, health and the OpenAPI document; every API read with DEMCAL_OPEN_READS."""
    if settings.open_reads or not (path == API_PREFIX or path.startswith(API_PREFIX + "/")):
        return True
    return path in OPEN_API_PATHS


def install_token_guard(app: FastAPI, settings: Settings) -> None:
    """Writes, and API reads unless opened, need a token whenever one is configured (always, off
    loopback); the token's user is stored as ``request.state.client_name`` and ``request.state.is_admin``."""
    table = token_users(settings)
    if not table:
        return

    @app.middleware("http")
    async def _require_token(request: Request, call_next):
        header = request.headers.get("authorization", "")
        scheme, _, supplied = header.partition(" ")
        user = _match(table, supplied.strip()) if scheme.lower() == "bearer" else None
        request.state.client_name = user.name if user else None
        request.state.is_admin = bool(user and user.admin)
        if user is None and (request.method in WRITE_METHODS or not read_is_open(request.url.path, settings)):
            what = "writes" if request.method in WRITE_METHODS else "reads (unless DEMCAL_OPEN_READS=1)"
            err = Unauthorized(f"missing or wrong bearer token: {what} need one on this server",
                               ["header", "Authorization"])
            return JSONResponse({"detail": err.detail()}, status_code=401, headers={"WWW-Authenticate": "Bearer"})
        return await call_next(request)


def trusted_proxies(settings: Settings) -> tuple:
    """The networks of DEMCAL_TRUSTED_PROXIES (``127.0.0.1,10.0.0.0/8``); a bad entry stops the start."""
    networks = []
    for item in (settings.trusted_proxies or "").split(","):
        if not item.strip():
            continue
        try:
            networks.append(ipaddress.ip_network(item.strip(), strict=False))
        except ValueError:
            raise SystemExit(f"DEMCAL_TRUSTED_PROXIES: {item.strip()!r} is not an address or network") from None
    return tuple(networks)


def _trusted(address: str | None, networks: tuple) -> bool:
    if not address or not networks:
        return False
    try:
        ip = ipaddress.ip_address(address.strip().strip("[]"))
    except ValueError:
        return False
    return any(ip in network for network in networks)


def _settings_of(request: Request) -> Settings | None:
    return getattr(request.app.state, "settings", None)


def peer_address(request: Request) -> str | None:
    """The client's address: the TCP peer, or, when the peer is a listed proxy, the nearest address in
    ``X-Forwarded-For`` that is not itself a listed proxy (the ones to its left are the client's word)."""
    peer = request.client.host if request.client else None
    settings = _settings_of(request)
    networks = trusted_proxies(settings) if settings is not None else ()
    if not _trusted(peer, networks):
        return peer
    hops = [hop.strip() for hop in ",".join(request.headers.getlist("x-forwarded-for")).split(",") if hop.strip()]
    for hop in reversed(hops):
        if not _trusted(hop, networks):
            return hop
    return hops[0] if hops else peer


def from_trusted_proxy(request: Request) -> bool:
    settings = _settings_of(request)
    peer = request.client.host if request.client else None
    return settings is not None and _trusted(peer, trusted_proxies(settings))


def client_id(request: Request, x_client_id: str | None = Header(
        None, min_length=1, max_length=100,
        description="client identity for per-client limits; honoured only from a proxy listed in "
                    "DEMCAL_TRUSTED_PROXIES (with a token, the identity is the token's name)")) -> str:
    """Who per-client limits count against: the token's name; else, from a listed proxy, X-Client-Id;
    else the client's address (``peer_address``). Nobody else can choose an identity by header."""
    name = getattr(request.state, "client_name", None)
    if name:
        return f"{TOKEN_CLIENT_PREFIX}{name}"
    if x_client_id and from_trusted_proxy(request):
        return x_client_id
    return peer_address(request) or "anonymous"
