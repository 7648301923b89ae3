"""Network helpers of the service tests, in a module of their own: ``from conftest import ...`` finds
whichever test folder's conftest loaded first when the whole suite runs."""
from __future__ import annotations

import socket
import subprocess
import time

import httpx

# The peer address TestClient reports: a loopback one, as for a local user (its default, "testclient", is
# not an address, and the identity rules treat it as a remote peer).
LOOPBACK_PEER = ("127.0.0.1", 50000)
# The URL TestClient sends its requests to: the service answers only Host names it knows (loopback by default,
# service.browser_guard), and TestClient's default "testserver" is not one of them.
LOCAL_BASE_URL = "http://127.0.0.1"


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


def wait_healthy(base_url: str, proc: subprocess.Popen, timeout_s: float = 90.0) -> None:
    """Generous: a fresh database is migrated before the port opens, and CI machines are shared."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if proc.poll() is not None:
            raise RuntimeError(f"server exited with {proc.returncode}")
        try:
            if httpx.get(f"{base_url}/api/v1/health", timeout=1.0).status_code == 200:
                return
        except httpx.HTTPError:
            pass
        time.sleep(0.1)
    raise TimeoutError("server did not become healthy")
