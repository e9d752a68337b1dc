"""Fixtures shared by every test file. Owned by the lead: ask before adding here."""

from __future__ import annotations

import socket
from collections.abc import Callable

import pytest


def _free_tcp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture
def free_tcp_port() -> Callable[[], int]:
    """Call it for a TCP port on 127.0.0.1 that was free a moment ago."""
    return _free_tcp_port
