"""What every HTTP-client CLI command shares: the client, errors as one line, tables, --json.

Any error (HTTP 4xx/5xx, no server, bad input file) is a one-line message on stderr and exit
status 2, never a traceback.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path
from typing import Any

import httpx

DEFAULT_URL = "http://127.0.0.1:8000"
TIMEOUT_S = 30.0


class CliError(Exception):
    pass


def client(args) -> httpx.Client:
    headers = {"X-Client-Id": "demcal-cli"}
    token = args.token or os.environ.get("DEMCAL_TOKEN")
    if token:
        headers["Authorization"] = f"Bearer {token}"
    return httpx.Client(base_url=args.url.rstrip("/") + "/api/v1", headers=headers, timeout=TIMEOUT_S)


def call(args, method: str, path: str, body: Any = None, params: dict | None = None) -> Any:
    try:
        with client(args) as http:
            response = http.request(method, path, json=body, params=params)
    except httpx.HTTPError as exc:
        raise CliError(f"cannot reach {args.url}: {exc}") from exc
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


def emit(args, data: Any, text: str | None = None) -> int:
    print(json.dumps(data, indent=1) if args.json or text is None else text)
    return 0


def guard(func):
    def run(args) -> int:
        try:
            return func(args)
        except CliError as exc:
            print(f"demcal: {exc}", file=sys.stderr)
            return 2
        except BrokenPipeError:  # the reader left early (``| head``): not an error of ours
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            return 0
    return run


def leaf(sub, name: str, func, help_text: str, aliases: tuple[str, ...] = ()) -> argparse.ArgumentParser:
    parser = sub.add_parser(name, help=help_text, description=help_text, aliases=list(aliases))
    parser.add_argument("--url", default=os.environ.get("DEMCAL_URL", DEFAULT_URL), help="service base URL")
    parser.add_argument("--token", default=None, help="bearer token for writes (or $DEMCAL_TOKEN)")
    parser.add_argument("--json", action="store_true", help="print the API's JSON")
    parser.set_defaults(func=guard(func))
    return parser
