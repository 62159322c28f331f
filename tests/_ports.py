"""Ports for a server a test starts that must be told its port (it cannot say which one the kernel
gave it): chosen free, then let go, so another program may take one before the server binds it.
A test that uses them retries with another choice when the server says so."""

from __future__ import annotations

import socket


def free_port_pair() -> int:
    """A loopback port N with N+1 free too (Groot2 serves on both), free when asked."""
    for _ in range(50):
        with socket.socket() as first, socket.socket() as second:
            first.bind(("127.0.0.1", 0))
            port = int(first.getsockname()[1])
            try:
                second.bind(("127.0.0.1", port + 1))
            except OSError:
                continue
            return port
    raise AssertionError("no two consecutive free ports on 127.0.0.1")
