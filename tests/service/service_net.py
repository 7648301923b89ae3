"""Network helpers of the service tests, in a module of their own: ``from conftest import ...`` finds
whichever test folder's conftest loaded first when the whole suite runs."""
from __future__ import annotations

import socket

# The peer address TestClient reports: a loopback one, as for a local user (its default, "testclient", is
# not an address, and the identity rules treat it as a remote peer).
LOOPBACK_PEER = ("127.0.0.1", 50000)


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]
