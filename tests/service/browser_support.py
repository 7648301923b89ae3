"""Headless Chromium against a real ``demcal serve``: the harness of the browser tests (test_browser.py)
and of the screenshot refresher (docs/screenshots/refresh.py).

Why Debian's chromium and Playwright from PyPI: Playwright drives the browser the CI machine installs
with apt (``executable_path``), so no browser is ever downloaded. Where no browser is present the tests
skip with the reason, except when ``DEMCAL_REQUIRE_BROWSER=1`` (set by .ci/run): then they fail.

Every page is watched: a console error, an uncaught page error or a request to anything but the
service itself (aborted by route interception) fails the test that caused it.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import urlparse

import httpx

from service_net import free_port, wait_healthy

CHROMIUM_CANDIDATES = ("/usr/bin/chromium", "/usr/bin/chromium-browser")
REQUIRE_ENV = "DEMCAL_REQUIRE_BROWSER"
REPO_ROOT = Path(__file__).resolve().parents[2]


def chromium_path() -> str | None:
    explicit = os.environ.get("DEMCAL_CHROMIUM")
    if explicit:
        return explicit if Path(explicit).exists() else None
    for path in CHROMIUM_CANDIDATES:
        if Path(path).exists():
            return path
    return shutil.which("chromium")


def missing_browser_reason() -> str | None:
    """None when the browser tests can run; else why not."""
    try:
        import playwright.sync_api  # noqa: F401
    except ImportError:
        return "playwright is not installed (pip install -e '.[test]')"
    if chromium_path() is None:
        return "no Chromium found (Debian: apt-get install chromium; or set DEMCAL_CHROMIUM)"
    return None


@dataclass
class LiveService:
    """``demcal serve`` on a free loopback port with a temp data dir, workers and the campaign ticker."""

    base_url: str
    database_url: str
    proc: subprocess.Popen
    data_dir: Path

    def api(self, method: str, path: str, **kwargs) -> httpx.Response:
        return httpx.request(method, f"{self.base_url}/api/v1{path}", timeout=30.0, **kwargs)


def start_service(data_dir: Path, workers: int = 1, **env_extra: str) -> LiveService:
    port = free_port()
    database_url = f"sqlite:///{(data_dir / 'demcal.db').as_posix()}"
    env = dict(os.environ)
    # the served code is this checkout's, not whichever one the package is installed (editable) from:
    # the service runs in data_dir, where `python -m service.cli` would otherwise import the installed copy
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(REPO_ROOT), env.get("PYTHONPATH", "")) if p)
    env.update({"DEMCAL_DATABASE_URL": database_url, "DEMCAL_SEED_MATERIALS": "true", "DEMCAL_LOG_LEVEL": "WARNING",
                "DEMCAL_TICK_INTERVAL_S": "0.3", "DEMCAL_POLL_INTERVAL_S": "0.1", "PYTHONUNBUFFERED": "1"})
    env.update(env_extra)
    proc = subprocess.Popen([sys.executable, "-m", "service.cli", "serve", "--port", str(port), "--workers", str(workers)],
                            env=env, cwd=data_dir)
    base_url = f"http://127.0.0.1:{port}"
    try:
        wait_healthy(base_url, proc)
    except (RuntimeError, TimeoutError):
        stop_service(proc)
        raise
        time.sleep(0.1)
    return LiveService(base_url, database_url, proc, data_dir)


def stop_service(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


@dataclass
class Watch:
    """What a page did wrong: console errors, page errors, requests that left the service."""

    base_host: str
    console_errors: list[str] = field(default_factory=list)
    page_errors: list[str] = field(default_factory=list)
    external_requests: list[str] = field(default_factory=list)
    allowed: list[str] = field(default_factory=list)  # substrings of console errors a test expects

    def problems(self) -> list[str]:
        unexpected = [m for m in self.console_errors if not any(a in m for a in self.allowed)]
        return ([f"console error: {m}" for m in unexpected] + [f"page error: {m}" for m in self.page_errors]
                + [f"request outside the service: {u}" for u in self.external_requests])


def watch_page(page, base_url: str) -> Watch:
    watch = Watch(urlparse(base_url).netloc)

    def route(route_obj):
        url = route_obj.request.url
        parsed = urlparse(url)
        if parsed.scheme in ("data", "blob") or parsed.netloc == watch.base_host:
            route_obj.continue_()
        else:
            watch.external_requests.append(url)
            route_obj.abort()

    page.route("**/*", route)
    page.on("console", lambda msg: watch.console_errors.append(f"{msg.text} @ {msg.location.get('url', '')}")
            if msg.type == "error" else None)
    page.on("pageerror", lambda exc: watch.page_errors.append(str(exc)))
    return watch


def screenshot_dir(default: Path | None = None) -> Path:
    path = Path(os.environ.get("DEMCAL_SCREENSHOT_DIR") or default or tempfile.mkdtemp(prefix="demcal-screens-"))
    path.mkdir(parents=True, exist_ok=True)
    return path


def launch(playwright):
    return playwright.chromium.launch(executable_path=chromium_path(), headless=True,
                                      args=["--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu"])
