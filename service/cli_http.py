"""What every HTTP-client CLI command shares: the service's URL, the client, errors as one line,
tables, --json, --quiet and --watch.

Any error (HTTP 4xx/5xx, no server, bad input file) is a one-line message on stderr and exit
status 2, never a traceback.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import httpx

TIMEOUT_S = 30.0
# a server bound to every interface is reached on loopback from its own machine
_WILDCARD_HOSTS = ("0.0.0.0", "::", "")
POINT_ELSEWHERE = "give --url, or set DEMCAL_URL (or DEMCAL_HOST and DEMCAL_PORT, as for demcal serve)"


class CliError(Exception):
    pass


def service_url(args) -> tuple[str, str]:
    """The service's base URL and where it came from. One rule for every client command: ``--url``,
    then $DEMCAL_URL, then $DEMCAL_HOST/$DEMCAL_PORT (so the variables that move ``demcal serve`` move
    the CLI with it), then the server's own defaults (service.config.Settings)."""
    from service.config import Settings

    if getattr(args, "url", None):
        return args.url.rstrip("/"), "--url"
    if os.environ.get("DEMCAL_URL"):
        return os.environ["DEMCAL_URL"].rstrip("/"), "DEMCAL_URL"
    host_env, port_env = os.environ.get("DEMCAL_HOST"), os.environ.get("DEMCAL_PORT")
    host = host_env or Settings.model_fields["host"].default
    port = port_env or str(Settings.model_fields["port"].default)
    if not port.isdigit() or not 0 < int(port) <= 65535:
        raise CliError(f"DEMCAL_PORT {port!r} is not a port number; {POINT_ELSEWHERE}")
    host = "127.0.0.1" if host in _WILDCARD_HOSTS else host
    host = f"[{host}]" if ":" in host else host
    source = " and ".join(n for n, v in (("DEMCAL_HOST", host_env), ("DEMCAL_PORT", port_env)) if v) or "the default"
    return f"http://{host}:{port}", source


def client(args, base_url: str) -> httpx.Client:
    headers = {"X-Client-Id": "demcal-cli"}
    token = args.token or os.environ.get("DEMCAL_TOKEN")
    if token:
        headers["Authorization"] = f"Bearer {token}"
    return httpx.Client(base_url=base_url + "/api/v1", headers=headers, timeout=TIMEOUT_S)


def call(args, method: str, path: str, body: Any = None, params: dict | None = None) -> Any:
    url, source = service_url(args)
    try:
        with client(args, url) as http:
            response = http.request(method, path, json=body, params=params)
    except httpx.HTTPError as exc:
        reason = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise CliError(f"cannot reach the service at {url} (from {source}): {reason}; is `demcal serve` "
                       f"running there? To use another service, {POINT_ELSEWHERE}") from exc
    if response.status_code == 204:
        return None
    try:
        data = response.json()
    except ValueError:
        data = {"detail": [{"loc": [], "msg": response.text[:200]}]}
    if response.status_code >= 400:
        detail = data.get("detail") if isinstance(data, dict) else None
        first = detail[0] if isinstance(detail, list) and detail else {"msg": str(detail), "loc": []}
        where = ".".join(str(p) for p in first.get("loc", []))
        raise CliError(f"HTTP {response.status_code}: {first.get('msg')}" + (f" (at {where})" if where else ""))
    return data


def read_json(path: str) -> Any:
    try:
        text = sys.stdin.read() if path == "-" else Path(path).read_text()
        return json.loads(text)
    except (OSError, json.JSONDecodeError) as exc:
        raise CliError(f"cannot read JSON from {path}: {exc}") from exc


def pairs(items: list[str] | None, what: str, cast=float) -> dict:
    out = {}
    for item in items or []:
        key, sep, value = item.partition("=")
        if not sep:
            raise CliError(f"{what} {item!r}: expected NAME=VALUE")
        try:
            out[key.strip()] = cast(value)
        except ValueError as exc:
            raise CliError(f"{what} {item!r}: {exc}") from exc
    return out


def fmt(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.5g}"
    if value is None:
        return "-"
    if isinstance(value, dict):
        return ", ".join(f"{k}={fmt(v)}" for k, v in value.items()) or "-"
    return str(value)


def table(headers: list[str], rows: list[list[Any]]) -> str:
    cells = [[fmt(c) for c in row] for row in rows]
    widths = [max([len(h)] + [len(r[i]) for r in cells]) for i, h in enumerate(headers)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(headers, widths)), "  ".join("-" * w for w in widths)]
    lines += ["  ".join(c.ljust(w) for c, w in zip(row, widths)) for row in cells]
    return "\n".join(lines)


def page_options(parser) -> None:
    """``--limit`` and ``--offset`` of a list command (the listing's own page; the service bounds the limit)."""
    parser.add_argument("--limit", type=int, help="rows per page (the service's default if not given)")
    parser.add_argument("--offset", type=int, help="rows to skip: the next page starts at offset + limit")


def page_params(args, **filters) -> dict:
    """Query parameters of a list command: its filters and page, the unset ones left out."""
    values = {**filters, "limit": getattr(args, "limit", None), "offset": getattr(args, "offset", None)}
    return {k: v for k, v in values.items() if v is not None}


def page_footer(page: dict) -> str:
    """Under a listing's table: how many of the total it shows, and how to see the next page."""
    shown, offset, total = len(page["items"]), page["offset"], page["total"]
    if offset == 0 and shown == total:
        return f"\n{total} in all"
    text = f"\n{offset + 1 if shown else offset}-{offset + shown} of {total}"
    return text + (f" (next page: --offset {offset + shown})" if offset + shown < total else "")


def emit(args, data: Any, text: str | None = None) -> int:
    if getattr(args, "quiet", False):  # scripts capture the new id: id=$(demcal job submit ... -q)
        print(data["id"])
    else:
        print(json.dumps(data, indent=1) if args.json or text is None else text)
    # what the service stored but doubts (a value outside what granular materials measure, the likely unit
    # slip named): on stderr, so a script capturing the id with -q still sees it
    for warning in (data.get("warnings") or []) if isinstance(data, dict) else []:
        print(f"demcal: warning: {warning}", file=sys.stderr)
    return 0


def bar(done: int, total: int, width: int = 24) -> str:
    """``[#########...............] 7/19``: a progress bar for a count known in advance."""
    filled = round(width * done / total) if total else 0
    return f"[{'#' * filled}{'.' * (width - filled)}] {done}/{total}"


def watch(args, fetch, render, finished) -> Any:
    """Print ``render(state)`` whenever it changes, polling ``fetch()`` every --interval seconds until
    ``finished(state)``; returns the last state. On a terminal the status is redrawn in place; in a log
    or a pipe every change is a line of its own, so the log shows the progress."""
    redraw = sys.stdout.isatty()
    shown = None
    while True:
        state = fetch()
        text, done = render(state), finished(state)
        if text != shown:
            print("\r\033[K" + text if redraw else text, end="" if redraw and not done else "\n", flush=True)
            shown = text
        elif redraw and done:
            print()
        if done:
            return state
        time.sleep(args.interval)


def watch_options(parser: argparse.ArgumentParser, what: str) -> None:
    parser.add_argument("--watch", action="store_true", help=f"follow it until {what}, redrawing on every change")
    parser.add_argument("--interval", type=_seconds, default=2.0, help="seconds between polls with --watch (default 2)")


def _seconds(text: str) -> float:
    value = float(text)
    if not 0.05 <= value <= 3600:  # a tighter loop only loads the service
        raise argparse.ArgumentTypeError(f"{text!r} is not between 0.05 and 3600 seconds")
    return value


def guard(func):
    def run(args) -> int:
        try:
            return func(args)
        except CliError as exc:
            print(f"demcal: {exc}", file=sys.stderr)
            return 2
        except KeyboardInterrupt:  # Ctrl-C ends a --watch: the campaign or job goes on regardless
            print(file=sys.stderr)
            return 130
        except BrokenPipeError:  # the reader left early (``| head``): not an error of ours
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
    return run


def leaf(sub, name: str, func, help_text: str, aliases: tuple[str, ...] = (),
         creates: bool = False) -> argparse.ArgumentParser:
    """A client command with the options every one shares; ``creates``: it makes something with an id,
    which --quiet prints alone."""
    parser = sub.add_parser(name, help=help_text, description=help_text, aliases=list(aliases))
    parser.add_argument("--url", default=None, help="service base URL (default $DEMCAL_URL, else "
                        "http://$DEMCAL_HOST:$DEMCAL_PORT, else http://127.0.0.1:8000)")
    parser.add_argument("--token", default=None, help="bearer token (or $DEMCAL_TOKEN): writes need one, and reads too when the server "
                        "has tokens")
    output = parser.add_mutually_exclusive_group()
    output.add_argument("--json", action="store_true", help="print the API's JSON")
    if creates:
        output.add_argument("--quiet", "-q", action="store_true",
                            help="print only the new id, e.g. id=$(demcal ... -q)")
    parser.set_defaults(func=guard(func))
    return parser
