"""SVG snapshots of the console with a fixed fleet state (tui.demo), at 80x24 and larger.

Regenerate after an intended change of the screen with
``pytest tests/test_tui_snapshots.py --snapshot-update`` and look at the SVGs before committing.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from typing import Any

import pytest

from tui.app import ConsoleApp
from tui.demo import DEMO_TIME_S, demo_mixed_model, demo_mixed_settings, demo_model, demo_settings

pytestmark = pytest.mark.timeout(120)


@pytest.fixture(autouse=True)
def utc(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Clock times on screen are local; pin the zone so the pictures do not depend on it."""
    monkeypatch.setenv("TZ", "UTC")
    time.tzset()
    yield
    monkeypatch.undo()
    time.tzset()


def demo_app() -> ConsoleApp:
    settings = demo_settings()
    return ConsoleApp(settings, model=demo_model(settings), clock=lambda: DEMO_TIME_S)


async def settle(pilot: Any) -> None:
    await pilot.pause()
    pilot.app.redraw()
    await pilot.pause()


SnapCompare = Callable[..., bool]


def test_main_screen_80x24(snap_compare: SnapCompare) -> None:
    assert snap_compare(demo_app(), terminal_size=(80, 24), run_before=settle)


def test_main_screen_130x40(snap_compare: SnapCompare) -> None:
    assert snap_compare(demo_app(), terminal_size=(130, 40), run_before=settle)


def test_vehicle_detail_screen(snap_compare: SnapCompare) -> None:
    async def open_detail(pilot: Any) -> None:
        await pilot.press("d")
        await settle(pilot)

    assert snap_compare(demo_app(), terminal_size=(100, 30), run_before=open_detail)


def test_emergency_stop_confirmation(snap_compare: SnapCompare) -> None:
    async def ask(pilot: Any) -> None:
        await settle(pilot)
        await pilot.press("e")
        await pilot.pause()

    assert snap_compare(demo_app(), terminal_size=(80, 24), run_before=ask)


def test_main_screen_200x60(snap_compare: SnapCompare) -> None:
    assert snap_compare(demo_app(), terminal_size=(200, 60), run_before=settle)


def test_help_screen_80x24(snap_compare: SnapCompare) -> None:
    async def ask(pilot: Any) -> None:
        await settle(pilot)
        await pilot.press("question_mark")
        await pilot.pause()

    assert snap_compare(demo_app(), terminal_size=(80, 24), run_before=ask)


def test_reject_asks_with_a_reason_80x24(snap_compare: SnapCompare) -> None:
    async def ask(pilot: Any) -> None:
        await settle(pilot)
        await pilot.press("tab", "r", *"not a letter")
        await pilot.pause()

    assert snap_compare(demo_app(), terminal_size=(80, 24), run_before=ask)


def test_marked_jobs_of_a_client_100x30(snap_compare: SnapCompare) -> None:
    async def mark(pilot: Any) -> None:
        await settle(pilot)
        await pilot.press("tab", "M")  # every waiting job of kiosk-7
        await pilot.pause()

    assert snap_compare(demo_app(), terminal_size=(100, 30), run_before=mark)


def test_bulk_reject_asks_once_80x24(snap_compare: SnapCompare) -> None:
    async def ask(pilot: Any) -> None:
        await settle(pilot)
        await pilot.press("tab", "M", "R")
        await pilot.pause()

    assert snap_compare(demo_app(), terminal_size=(80, 24), run_before=ask)


def mixed_app() -> ConsoleApp:
    """A brush quadrotor on a table, the hexarotor on a wall (with its force), a ground writer."""
    settings = demo_mixed_settings()
    return ConsoleApp(settings, model=demo_mixed_model(), clock=lambda: DEMO_TIME_S)


def test_mixed_fleet_130x40(snap_compare: SnapCompare) -> None:
    assert snap_compare(mixed_app(), terminal_size=(130, 40), run_before=settle)


def test_wall_writer_detail_with_its_force(snap_compare: SnapCompare) -> None:
    async def open_detail(pilot: Any) -> None:
        await settle(pilot)
        await pilot.press("down", "d")
        await settle(pilot)
        await settle(pilot)  # the force plot appears with the first force, then is drawn
        await pilot.wait_for_scheduled_animations()
        await pilot.pause(0.2)  # the footer lists the screen's keys a moment after it opens

    assert snap_compare(mixed_app(), terminal_size=(100, 30), run_before=open_detail)
