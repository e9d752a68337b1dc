"""Keys of the operator console driven by Pilot on the demo show (no bus: ``link=None``).

Without a link every command is answered ``offline``, and the model records the command the
console tried to send (``model.last_reply``): that is what these tests read.
"""

from __future__ import annotations

import asyncio
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from bus.messages import OperatorCommand, ShowSnapshot, VehicleStatus, VehicleSummary
from tui.app import ConsoleApp
from tui.demo import DEMO_TIME_S, demo_model, demo_settings
from tui.widgets.board_strip import SYMBOLS, strip_text
from tui.widgets.confirm_screen import ConfirmScreen
from tui.widgets.help_screen import BOARD_MARKS, HELP, HelpScreen
from tui.widgets.preview_screen import PreviewScreen
from tui.widgets.vehicle_detail_screen import VehicleDetailScreen

pytestmark = pytest.mark.timeout(60)

Scenario = Callable[[ConsoleApp, Any], Awaitable[None]]


def play(scenario: Scenario, size: tuple[int, int] = (100, 30)) -> ConsoleApp:
    settings = demo_settings()
    app = ConsoleApp(settings, model=demo_model(settings), clock=lambda: DEMO_TIME_S)

    async def main() -> None:
        async with app.run_test(size=size) as pilot:
            await pilot.pause()
            await scenario(app, pilot)

    asyncio.run(main())
    return app


async def settle(pilot: Any) -> None:
    for _ in range(3):
        await pilot.pause(0.02)


def sent(app: ConsoleApp) -> OperatorCommand | None:
    return None if app.model.last_reply is None else app.model.last_reply[0]


def test_escape_and_q_leave_the_vehicle_view_without_quitting() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        for back in ("escape", "q"):
            await pilot.press("enter")
            await settle(pilot)
            assert isinstance(app.screen, VehicleDetailScreen)
            await pilot.press(back)
            await settle(pilot)
            assert not isinstance(app.screen, VehicleDetailScreen) and app.is_running

    play(scenario)


def test_quit_while_vehicles_fly_asks_and_says_the_show_goes_on() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        assert app.model.airborne_count() == 2  # uav1 writing, uav2 taking off
        await pilot.press("q")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen)
        assert "flying" in app.screen.question and "keeps running" in app.screen.question
        await pilot.press("n")
        await settle(pilot)
        assert app.is_running and not isinstance(app.screen, ConfirmScreen)
        await pilot.press("q")
        await settle(pilot)
        await pilot.press("y")
        await settle(pilot)
        assert not app.is_running
        assert sent(app) is None  # quitting sends nothing to the show

    play(scenario)


@pytest.mark.parametrize("key", ["q", "ctrl+c"])
def test_quit_on_the_ground_is_immediate(key: str) -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        for vid in ("uav1", "uav2"):
            status = VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="landed")
            app.model.apply(status, DEMO_TIME_S)
        await pilot.press(key)
        await settle(pilot)
        assert not app.is_running

    play(scenario)


def test_ctrl_c_while_vehicles_fly_asks_as_q_does() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await pilot.press("ctrl+c")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen) and "keeps running" in app.screen.question

    play(scenario)


def test_land_is_confirmed_and_the_held_vehicle_shows_in_the_fleet() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await pilot.press("l")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen) and "held" in app.screen.question
        await pilot.press("y")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="land", vehicle_id="uav1")
        await pilot.press("u")  # not held yet: refused without a question
        await settle(pilot)
        assert not isinstance(app.screen, ConfirmScreen)
        summary = VehicleSummary(
            vehicle_id="uav1", kind="quadrotor-brush", state="landed", alive=True, held=True
        )
        fleet = ShowSnapshot(
            show_id="demo-show", time_s=0, queue_paused=False, jobs=[], vehicles=[summary]
        )  # a ``fleet`` publication, after the vehicle's own telemetry went quiet
        app.model.apply(fleet, DEMO_TIME_S + 100)
        await pilot.pause(0.3)
        assert app._fleet.cell_text("uav1", "state") == "landed held"
        await pilot.press("u")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("y")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="release", vehicle_id="uav1")

    play(scenario)


def test_p_pauses_the_selected_vehicle_at_once_and_resuming_it_is_confirmed() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await pilot.press("P")
        await settle(pilot)
        assert not isinstance(app.screen, ConfirmScreen)  # no new job: nothing to confirm
        assert sent(app) == OperatorCommand(command="pause", vehicle_id="uav1")
        summary = VehicleSummary(
            vehicle_id="uav1", kind="quadrotor-brush", state="idle", alive=True, paused=True
        )
        fleet = ShowSnapshot(
            show_id="demo-show", time_s=0, queue_paused=False, jobs=[], vehicles=[summary]
        )
        app.model.apply(fleet, DEMO_TIME_S + 100)
        await pilot.pause(0.3)
        assert app._fleet.cell_text("uav1", "state") == "idle paused"
        await pilot.press("P")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen) and "fly" in app.screen.question
        await pilot.press("y")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="resume", vehicle_id="uav1")

    play(scenario)


def test_release_all_asks_once_and_releases_every_held_vehicle() -> None:
    """After an E-STOP or a land of the whole fleet: ``U`` names the held vehicles, says the
    paused queue stays paused, and sends one ``release_all``."""

    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await pilot.press("U")  # nothing held: refused without a question
        await settle(pilot)
        assert not isinstance(app.screen, ConfirmScreen) and sent(app) is None
        held = [
            VehicleSummary(
                vehicle_id=v, kind="quadrotor-brush", state="landed", alive=True, held=True
            )
            for v in ("uav1", "uav2")
        ]
        fleet = ShowSnapshot(
            show_id="demo-show", time_s=0, queue_paused=True, jobs=[], vehicles=held
        )
        app.model.apply(fleet, DEMO_TIME_S + 100)
        await pilot.pause(0.3)
        await pilot.press("U")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen)
        question = app.screen.question
        assert "uav1" in question and "uav2" in question and "paused" in question
        await pilot.press("y")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="release_all")

    play(scenario)


def test_job_keys_act_only_on_the_visible_selection_of_the_focused_queue() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        assert app.focused is app._fleet
        await pilot.press("a", "r", "c", "plus")
        await settle(pilot)
        assert sent(app) is None and not isinstance(app.screen, ConfirmScreen)
        await pilot.press("tab")
        await settle(pilot)
        assert app.focused is app._queue and app._queue.selected_job == "j-0006"
        await pilot.press("l")  # a vehicle key: the fleet's cursor is out of focus
        await settle(pilot)
        assert sent(app) is None and not isinstance(app.screen, ConfirmScreen)
        await pilot.press("plus")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="prioritize", job_id="j-0006", priority=1)
        await pilot.press("r")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press(*"not a letter y", "enter")  # y and n are part of the reason here
        await settle(pilot)
        assert sent(app) == OperatorCommand(
            command="reject", job_id="j-0006", reason="not a letter y"
        )
        await pilot.press("down", "c")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen)
        await pilot.press("escape")
        await settle(pilot)
        assert sent(app) is not None and sent(app).command == "reject"  # cancel not sent

    play(scenario)


def test_help_lists_every_key_and_the_preview_fills_the_screen() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await pilot.press("question_mark")
        await settle(pilot)
        assert isinstance(app.screen, HelpScreen)
        await pilot.press("escape")
        await settle(pilot)
        await pilot.press("f1")
        await settle(pilot)
        assert isinstance(app.screen, HelpScreen)
        await pilot.press("q")
        await settle(pilot)
        assert app.is_running and not isinstance(app.screen, HelpScreen)
        await pilot.press("tab", "v")
        await settle(pilot)
        assert isinstance(app.screen, PreviewScreen) and app.screen.job.job_id == "j-0006"
        assert app.screen.query_one("#preview-full").size.height >= 20
        await pilot.press("escape")
        await settle(pilot)
        assert not isinstance(app.screen, PreviewScreen)

    play(scenario)
    documented = " ".join(keys for keys, _, _ in HELP).replace("/", " ").split()
    for binding in ConsoleApp.BINDINGS:
        for key in binding.key.split(","):  # type: ignore[union-attr]
            shown = {
                "plus": "+",
                "minus": "-",
                "question_mark": "?",
                "f1": "F1",
                "ctrl+c": "Ctrl+C",
            }.get(key, key)
            assert shown in documented, f"key {key!r} missing from the help"
    for mark in [*(m for m, _ in SYMBOLS.values()), "^", "H", "P", "✎"]:
        assert f" {mark} " in BOARD_MARKS or f"{mark} " in BOARD_MARKS, f"{mark!r} unexplained"


def test_header_counts_faults_and_approvals_and_never_claims_a_stalled_queue_runs() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await settle(pilot)
        assert app._header.awaiting == 2
        assert any("2 submission(s) awaiting approval" in a for a in app._alerts.alerts)
        for vid in ("uav1", "uav2"):
            status = VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="fault")
            app.model.apply(status, DEMO_TIME_S)
        app.redraw()
        await settle(pilot)
        assert app._header.faults == 2 and app._header.can_fly == 0
        header = app._header.render().plain
        assert "NO VEHICLE CAN FLY" in header and "▶ queue" not in header
        assert "uav1 fault" in app._alerts.alerts
        await pilot.press("F")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen) and "2 vehicle(s)" in app.screen.question
        await pilot.press("y")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="clear_fault", vehicle_id="uav2")  # the last

    play(scenario)


def test_a_half_written_board_alerts_and_takes_a_confirmed_fresh_sheet() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await pilot.press("s")  # no board waits: refused, nothing asked
        await settle(pilot)
        assert not isinstance(app.screen, ConfirmScreen) and sent(app) is None
        fleet = ShowSnapshot(
            show_id="demo-show",
            time_s=DEMO_TIME_S,
            queue_paused=False,
            jobs=[],
            vehicles=[],
            dirty_boards=["b1"],
        )
        app.model.apply(fleet, DEMO_TIME_S)
        await pilot.pause(0.3)
        assert "b1 half-written: replace the sheet, then s" in app._alerts.alerts
        assert "HALF-WRITTEN" in app.query_one("#board-b1").title
        await pilot.press("s")
        await settle(pilot)
        assert isinstance(app.screen, ConfirmScreen) and "b1" in app.screen.question
        await pilot.press("y")
        await settle(pilot)
        assert sent(app) == OperatorCommand(command="fresh_sheet", board_id="b1")

    play(scenario)


def test_the_board_strip_names_every_board_in_whole_entries() -> None:
    for count, width, expected in (
        (3, 80, "b1 uav1 «工» 55% │ b2 uav2 taking off │ b3 uav3 lost"),
        (12, 80, "b1工 b2^ b3✖ b4· b5· b6· b7· b8· b9· b10· b11· b12·"),
        (12, 30, "b1工 b2^ b3✖ b4· b5· b6· +6"),
    ):
        settings = demo_settings(count)
        shown = strip_text(demo_model(settings), settings, DEMO_TIME_S, width).plain
        assert shown == expected and len(shown) <= width


def test_home_and_end_take_the_queue_cursor_to_the_first_and_the_last_job() -> None:
    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await pilot.press("tab")
        await settle(pilot)
        assert app.focused is app._queue
        await pilot.press("end")
        await settle(pilot)
        last = app._queue.selected_job
        await pilot.press("home")
        await settle(pilot)
        assert app._queue.selected_job == app._queue._keys[0] != last == app._queue._keys[-1]

    play(scenario)
