"""What a web page in the user's browser must not be able to do to this service.

A demcal server on loopback without a token trusts whoever can reach it, and a browser reaches it on
behalf of every page the user opens. Three doors are closed here (issue 32, item 3):

* **DNS rebinding**: a page on ``evil.example`` re-resolves its own name to 127.0.0.1 and then reads
  and writes the API as "same origin". Its requests still say ``Host: evil.example``, so only Host
  names the service knows are answered (``allowed_hosts``); any other gets 400.
* **Cross-site requests (CSRF)**: a form or ``fetch(..., {mode: "no-cors"})`` on another site can
  POST here without a preflight, but only with a form's content types (urlencoded, multipart,
  text/plain) or none. So a state-changing request (POST, PUT, PATCH, DELETE) is refused when its
  ``Origin`` (or, without one, its ``Referer``) is another site (403), and when its Content-Type is
  anything but JSON (415): the API reads only JSON, and a bodyless ``/jobs/{id}/cancel`` from a
  cross-site form always carries a form's content type, even from a browser that sends no Origin.
  curl, the CLI and httpx send neither header, so they pass unchanged.
* **Framing and content sniffing**: every response carries a Content-Security-Policy (scripts only
  from this service, plus the hashes of the API docs' inline start-up scripts), ``X-Frame-Options:
  DENY`` with ``frame-ancestors 'none'`` (no clickjacking of the cancel buttons),
  ``X-Content-Type-Options: nosniff`` and a Referrer-Policy.
"""
from __future__ import annotations

import json
from urllib.parse import urlsplit

from service.config import Settings
from service.security import WRITE_METHODS

LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
JSON_TYPES = ("application/json",)
DEFAULT_PORTS = {"http": 80, "https": 443, "ws": 80, "wss": 443}


def allowed_hosts(settings: Settings) -> frozenset[str] | None:
    """Host names (no port, lower case) the service answers to; None = any (``allowed_hosts='*'``).

    Loopback names always (the page, the CLI, health checks and Docker's port mapping reach the
    service through them); the bound host when it is a name or an address rather than "every
    interface"; and the operator's extra names, which a wildcard bind needs for other machines."""
    extra = [name.strip().lower() for name in (settings.allowed_hosts or "").split(",") if name.strip()]
    if "*" in extra:
        return None
    names = set(LOOPBACK_NAMES)
    bound = settings.host.strip().strip("[]").lower()
    if bound not in ("", "0.0.0.0", "::"):
        names.add(bound)
    names.update(name.strip("[]") for name in extra)
    return frozenset(names)


def split_host(netloc: str) -> tuple[str, int | None] | None:
    """``"[::1]:8000"`` -> ``("::1", 8000)``; ``"Example.org"`` -> ``("example.org", None)``; None if malformed."""
    try:
        parts = urlsplit(f"//{netloc}")
        return (parts.hostname or "").lower(), parts.port
    except ValueError:
        return None


def _origin_of(value: str) -> tuple[str, str, int | None] | None:
    """(scheme, host, port with the scheme's default filled in) of an Origin or Referer; None if opaque."""
    try:
        parts = urlsplit(value)
        port = parts.port
    except ValueError:
        return None
    if not parts.scheme or not parts.hostname:
        return None  # "null" (sandboxed frames, file: pages) names no site that could be this one
    return parts.scheme.lower(), parts.hostname.lower(), port or DEFAULT_PORTS.get(parts.scheme.lower())


def same_site(claimed: str, host_header: str) -> bool:
    """Whether an Origin/Referer names this very service: the host and port the request was sent to.
    Ports count: another local web app on localhost:3000 is another site. A Host without a port was
    sent to the default port of the browser's scheme, which the Origin names (behind a TLS proxy the
    service itself sees plain http, so its own scheme cannot tell)."""
    origin = _origin_of(claimed)
    target = split_host(host_header)
    if origin is None or target is None:
        return False
    target_port = target[1] or DEFAULT_PORTS.get(origin[0])
    return (origin[1], origin[2]) == (target[0], target_port)


def content_security_policy(script_hashes: tuple[str, ...] = ()) -> str:
    """``'self'`` everywhere; the exceptions are what the bundled pages need, each checked in Chromium
    (tests/service/test_browser.py fails on any CSP violation in the console):
    inline ``style`` attributes and ``<style>`` elements (without them Chromium reports 14 violations:
    the page's charts and ReDoc's styled components write them), ``data:`` images (Swagger UI's and
    ReDoc's icons are data URIs: 2 violations without), ``blob:`` workers (ReDoc's search index runs
    in a worker made from a Blob) and ``blob:`` images (Swagger UI shows an image response that way).
    The API docs' inline start-up script is allowed by its hash only, so no injected script can run."""
    scripts = " ".join(["'self'", *(f"'{digest}'" for digest in script_hashes)])
    return "; ".join([
        "default-src 'self'", f"script-src {scripts}", "style-src 'self' 'unsafe-inline'",
        "img-src 'self' data: blob:", "worker-src 'self' blob:",
        "connect-src 'self'", "object-src 'none'", "base-uri 'self'", "form-action 'self'",
        "frame-ancestors 'none'",
    ])


def _error(status: int, message: str, loc: list[str], error_type: str) -> tuple[int, bytes]:
    return status, json.dumps({"detail": [{"loc": loc, "msg": message, "type": error_type}]}).encode()


class BrowserGuard:
    """ASGI middleware, outermost, so that no route (nor the token guard) sees a refused request and
    every response, errors included, carries the security headers."""

    def __init__(self, app, settings: Settings, script_hashes: tuple[str, ...] = ()):
        self.app = app
        self.hosts = allowed_hosts(settings)
        self.headers = [
            (b"content-security-policy", content_security_policy(script_hashes).encode()),
            (b"x-frame-options", b"DENY"),
            (b"x-content-type-options", b"nosniff"),
            (b"referrer-policy", b"same-origin"),
        ]

    def refusal(self, scope) -> tuple[int, bytes] | None:
        headers = {key.decode("latin-1").lower(): value.decode("latin-1") for key, value in scope["headers"]}
        host_header = headers.get("host", "")
        target = split_host(host_header)
        if self.hosts is not None and (target is None or target[0] not in self.hosts):
            return _error(400, f"this service does not answer to Host {host_header!r}; add it to "
                               "DEMCAL_ALLOWED_HOSTS if it is this service's name", ["header", "Host"], "bad_host")
        if scope["method"] not in WRITE_METHODS:
            return None
        for name in ("origin", "referer"):  # Referer only when the browser sent no Origin
            if name in headers:
                if not same_site(headers[name], host_header):
                    return _error(403, f"cross-site request refused ({name.capitalize()} "
                                       f"{headers[name]!r} is not this service)", ["header", name.capitalize()],
                                  "cross_site")
                break
        content_type = headers.get("content-type")
        if content_type is not None and content_type.split(";")[0].strip().lower() not in JSON_TYPES:
            return _error(415, "state-changing requests take a JSON body (Content-Type: application/json) "
                               "or none; form and text bodies are refused so that no other web page can "
                               "post one", ["header", "Content-Type"], "unsupported_media_type")
        return None

    async def __call__(self, scope, receive, send):
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        refused = self.refusal(scope)

        async def send_with_headers(message):
            if message["type"] == "http.response.start":
                message = {**message, "headers": [*message.get("headers", []), *self.headers]}
            await send(message)

        if refused is not None:
            status, body = refused
            await send_with_headers({"type": "http.response.start", "status": status, "headers": [
                (b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]})
            await send_with_headers({"type": "http.response.body", "body": body})
            return
        await self.app(scope, receive, send_with_headers)


__all__ = ["LOOPBACK_NAMES", "BrowserGuard", "allowed_hosts", "content_security_policy", "same_site"]
