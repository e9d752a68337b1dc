"""Fixtures shared by every test file. Owned by the lead: ask before adding here."""

from __future__ import annotations

import socket
from collections.abc import Callable, Iterator

import pytest


def _free_tcp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.bind(("127.0.0.1", 0))
        return int(sock.getsockname()[1])


@pytest.fixture
def free_tcp_port() -> Callable[[], int]:
    """Call it for a TCP port on 127.0.0.1 that was free a moment ago."""
    return _free_tcp_port


@pytest.fixture(scope="module")
def wall_kiosk() -> Iterator[str]:
    """A kiosk (no show around it) whose previews are planned for the wall hexarotor: its URL."""
    from bus.session import loopback_settings
    from kiosk.service import serving
    from kiosk.settings import KioskSettings, kind_preview

    area_m = (0.5, 0.5)
    wall = kind_preview("hexarotor-sponge", area_m, KioskSettings.margin_m)
    settings = KioskSettings(
        show_id="kiosk-widths",
        port=0,
        writing_area_m=area_m,
        width_range_m=wall.kind.width_range_m(wall.settings),
        preview_kinds=(wall,),
    )
    with serving(settings, loopback_settings(), role="peer") as server:
        yield server.url


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Under xdist (`-n 2 --dist loadgroup`), tests that start processes or a browser run one at
    a time on one worker: they wait far more than they compute, and their timing bounds were set
    for a machine with a core to spare. Every other test is spread over the workers."""
    for item in items:
        timed = item.get_closest_marker("multiprocess") or item.get_closest_marker("browser")
        if timed or item.path.name in REAL_TIME_FILES:
            item.add_marker(pytest.mark.xdist_group("processes"))


REAL_TIME_FILES = frozenset({"test_mavlink_e2e.py"})
"""Tests in one process that still fly in real time against a clock of their own (a MAVLink
simulator in a thread): beside a busy worker they wrote 7.6 mm against 2.3 mm (a fresh clone's
CI run; 12 s and a pass alone)."""
