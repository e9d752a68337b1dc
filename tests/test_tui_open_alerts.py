"""A console that reconnects shows the alerts it missed: the orchestrator's open alerts from the
snapshot join its own, once per cause, until a later snapshot or fleet no longer has them."""

from __future__ import annotations

import asyncio

import pytest

from bus.messages import Event, ShowSnapshot
from tui.app import ConsoleApp
from tui.demo import DEMO_TIME_S, demo_settings
from tui.model import ConsoleModel

pytestmark = pytest.mark.timeout(60)


def _alert(kind: str, message: str, vehicle_id: str | None, time_s: float = 10.0) -> Event:
    return Event(time_s=time_s, level="alert", kind=kind, message=message, vehicle_id=vehicle_id)


OPEN = [
    _alert("vehicle_held", "uav1 held: in fault (motor 3); check it, then release it", "uav1"),
    _alert("operator", "ana: estop", None),
    _alert("board_dirty", "b2 half-written by 永: fresh sheet needed", "uav2"),
    _alert("vehicle_lost", "uav3 is lost: its token is gone", "uav3"),
]


def _snapshot(alerts: list[Event], *, lost: bool = False) -> ShowSnapshot:
    return ShowSnapshot(
        show_id="demo-show",
        time_s=DEMO_TIME_S,
        queue_paused=True,
        jobs=[],
        vehicles=[],
        dirty_boards=["b2"] if lost else [],
        alerts=alerts,
    )


def test_a_snapshot_brings_the_open_alerts_each_cause_once() -> None:
    model = ConsoleModel(demo_settings())
    assert model.alerts() == []
    model.apply_snapshot(_snapshot(OPEN), DEMO_TIME_S, full=True)
    shown = {a.key: (a.kind, a.message) for a in model.alerts()}
    assert shown == {
        "held:uav1": ("vehicle_held", OPEN[0].message),
        "held:*": ("vehicle_held", "ana: estop"),
        "sheet:b2": ("fresh_sheet", OPEN[2].message),
        "lost:uav3": ("vehicle_lost", OPEN[3].message),
    }
    model.apply_snapshot(_snapshot(OPEN, lost=True), DEMO_TIME_S + 1, full=False)  # a fleet
    sheet = [a for a in model.alerts() if a.key == "sheet:b2"]
    assert [a.message for a in sheet] == ["b2 half-written: replace the sheet, then s"]  # own
    assert model.acknowledge_alerts() == 4 and model.alerts() == []
    model.apply_snapshot(_snapshot([]), DEMO_TIME_S + 2, full=False)  # every cause gone
    assert model.alerts() == []
    model.apply_snapshot(_snapshot(OPEN[:1]), DEMO_TIME_S + 3, full=False)  # held again
    assert [a.key for a in model.alerts()] == ["held:uav1"]


def test_the_console_shows_the_alerts_it_missed_after_joining() -> None:
    settings = demo_settings()
    app = ConsoleApp(settings, clock=lambda: DEMO_TIME_S)

    async def main() -> None:
        async with app.run_test(size=(100, 30)) as pilot:
            await pilot.pause()
            app.model.apply_snapshot(_snapshot(OPEN[:2]), DEMO_TIME_S, full=True)
            app.redraw()
            await pilot.pause()
            assert app._alerts.alerts == (OPEN[0].message, "ana: estop")

    asyncio.run(main())
