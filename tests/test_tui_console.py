"""The operator console driven by Pilot against real Zenoh sessions on loopback.

A fake orchestrator in the test speaks the documented protocol (``snapshot`` and ``command``
queryables, ``jobs/<id>`` and ``vehicles/<id>/status`` publications, liveliness tokens), so the
console's whole path is real: Zenoh threads -> inbox -> model -> widgets, keys -> OperatorCommand.
"""

from __future__ import annotations

import asyncio
import io
import threading
import time
from collections.abc import Callable, Iterator
from typing import Any

import msgspec
import pytest
from rich.console import Console
from textual.widgets import Static

from bus.keys import ShowKeys
from bus.messages import (
    CommandReply,
    ErrorInfo,
    JobState,
    OperatorCommand,
    ShowSnapshot,
    Telemetry,
    VehicleStatus,
    VehicleSummary,
)
from bus.pubsub import declare_token, publish
from bus.rpc import serve
from bus.session import BusSettings, Session, loopback_settings, open_session
from tui.app import ConsoleApp
from tui.link import ConsoleLink
from tui.settings import BoardGeometry, ConsoleSettings, VehicleSpec
from tui.widgets.board_view import INK, BoardView
from tui.widgets.confirm_screen import ConfirmScreen
from tui.widgets.force_plot import MEASURED, TARGET, ForcePlot

pytestmark = pytest.mark.timeout(60)

SHOW = "tui-test"
KEYS = ShowKeys(SHOW)
SETTINGS = ConsoleSettings(
    show_id=SHOW,
    boards=(BoardGeometry("b1"),),
    vehicles=(VehicleSpec("uav1", "quadrotor-brush", "b1"),),
    tracking_error_alert_m=0.05,
)


def _job(job_id: str, state: str, label: str, **extra: Any) -> JobState:
    now = time.time()
    return JobState(
        job_id=job_id,
        state=state,
        label=label,
        kind="text",  # type: ignore[arg-type]
        client_id="kiosk",
        created_at_s=now,
        updated_at_s=now,
        **extra,
    )


class FakeOrchestrator:
    """The orchestrator's side of the console protocol, with canned behaviour."""

    def __init__(self, session: Session, jobs: list[JobState], vehicles: list[str]) -> None:
        self.session = session
        self.jobs = {job.job_id: job for job in jobs}
        self.vehicles = vehicles
        self.commands: list[OperatorCommand] = []
        self.snapshots = 0
        self._lock = threading.Lock()
        self._entities = [
            serve(session, KEYS.snapshot, None, self._snapshot),
            serve(session, KEYS.command, OperatorCommand, self._command),
        ]
        self.token: Any = declare_token(session, KEYS.orchestrator_alive)

    def _snapshot(self, _: None) -> ShowSnapshot:
        with self._lock:
            jobs = list(self.jobs.values())
            self.snapshots += 1
        summaries = [
            VehicleSummary(
                vehicle_id=v, kind="quadrotor-brush", state="idle", alive=True, board_id="b1"
            )
            for v in self.vehicles
        ]
        return ShowSnapshot(
            show_id=SHOW, time_s=time.time(), queue_paused=False, jobs=jobs, vehicles=summaries
        )

    def _command(self, command: OperatorCommand) -> CommandReply:
        with self._lock:
            self.commands.append(command)
        if command.command == "approve" and command.job_id in self.jobs:
            job = msgspec.structs.replace(
                self.jobs[command.job_id],
                state="queued",
                queue_position=1,
                eta_s=12.0,
                updated_at_s=time.time(),
            )
            self.jobs[job.job_id] = job
            publish(self.session, KEYS.job(job.job_id), job)
            return CommandReply(ok=True, message=f"{job.job_id} queued")
        if command.command == "land" and command.vehicle_id:
            status = VehicleStatus(
                vehicle_id=command.vehicle_id,
                kind="quadrotor-brush",
                state="landing",
                board_id="b1",
            )
            publish(self.session, KEYS.vehicle_status(command.vehicle_id), status)
            return CommandReply(ok=True, message=f"landing {command.vehicle_id}")
        if command.command == "estop":
            return CommandReply(ok=True, message="motors stopped")
        return CommandReply(ok=False, error=ErrorInfo(code="unsupported", message="not here"))

    def sent(self, name: str) -> list[OperatorCommand]:
        with self._lock:
            return [c for c in self.commands if c.command == name]

    def close(self) -> None:
        for entity in self._entities:
            entity.undeclare()


@pytest.fixture
def router() -> Iterator[tuple[BusSettings, Session]]:
    """A Zenoh router on a free loopback port (the show's hub); the fake orchestrator uses it."""
    settings = loopback_settings()
    with open_session(settings, role="router") as session:
        yield settings, session


async def until(pilot: Any, condition: Callable[[], object], what: str) -> None:
    """Let the app run until ``condition()`` holds (bounded, so a broken console fails)."""
    deadline = time.monotonic() + 10.0
    while not condition():
        if time.monotonic() > deadline:
            raise AssertionError(f"console never showed: {what}")
        await pilot.pause(0.05)


def run_console(
    settings: BusSettings,
    scenario: Callable[[ConsoleApp, Any], Any],
    console: ConsoleSettings = SETTINGS,
) -> None:
    """Open a console session (client of the router), run the app headless, play ``scenario``."""
    with open_session(settings, role="client") as session:
        app = ConsoleApp(console, link=ConsoleLink(session, KEYS))

        async def main() -> None:
            async with app.run_test(size=(100, 30)) as pilot:
                await scenario(app, pilot)

        asyncio.run(main())


def telemetry(i: int, *, pen_down: bool = True, error_m: float = 0.01) -> Telemetry:
    x = -0.3 + 0.02 * i
    return Telemetry(
        vehicle_id="uav1",
        t_s=0.05 * i,
        state="writing",
        position_m_enu=(x, 0.0, 0.25),
        velocity_mps_enu=(0.4, 0.0, 0.0),
        reference_m_enu=(x, 0.0, 0.25),
        pen_down=pen_down,
        tracking_error_m=error_m,
        battery_fraction=0.7,
        job_id="j-2",
        progress=i / 40,
    )


def test_late_joiner_approves_a_submission_and_sees_it_queued(router: Any) -> None:
    settings, session = router
    fake = FakeOrchestrator(
        session, [_job("j-1", "awaiting_approval", "永"), _job("j-9", "done", "山")], ["uav1"]
    )

    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await until(pilot, lambda: app.model.job("j-1") is not None, "the snapshot's jobs")
        assert app.model.orchestrator == "online"
        assert app.model.job("j-9") is not None  # finished jobs come with the snapshot
        app.query_one("#queue").focus()
        # awaiting approval is listed first, so the cursor starts on it
        await until(pilot, lambda: app._queue.selected_job == "j-1", "j-1 in the queue")
        await pilot.press("a")
        await until(pilot, lambda: fake.sent("approve"), "an approve command")
        assert fake.sent("approve")[0].job_id == "j-1"
        await until(pilot, lambda: app.model.job("j-1").state == "queued", "j-1 queued")
        await until(pilot, lambda: "queued" in app._header.last_reply, "the answer")
        await until(
            pilot, lambda: "ETA" in str(app._queue.get_row("j-1")[4]), "j-1's ETA in the queue"
        )
        assert str(app._queue.get_row("j-1")[0]) == "queued"

    run_console(settings, scenario)
    fake.close()


def test_lands_the_selected_vehicle_and_draws_its_path(router: Any) -> None:
    settings, session = router
    fake = FakeOrchestrator(session, [_job("j-2", "writing", "一", vehicle_id="uav1")], ["uav1"])
    token = declare_token(session, KEYS.vehicle_alive("uav1"))

    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await until(pilot, lambda: app.model.orchestrator == "online", "the orchestrator")
        for i in range(30):
            publish(session, KEYS.telemetry("uav1"), telemetry(i, pen_down=i >= 5))
        await until(pilot, lambda: app.model.track("uav1").count == 30, "30 telemetry samples")
        await until(pilot, lambda: app._fleet.cell_text("uav1", "state") == "writing", "writing")
        board = app.query_one(BoardView)
        await until(
            pilot,
            lambda: (
                board._canvas is not None
                and any(
                    board._canvas.get(x, y, INK)
                    for x in range(board._canvas.width_dots)
                    for y in range(board._canvas.height_dots)
                )
            ),
            "ink on the board",
        )
        assert "一" in board.title
        await pilot.press("l")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "a confirmation")
        assert fake.sent("land") == []  # not before the operator says yes
        await pilot.press("y")
        await until(pilot, lambda: fake.sent("land"), "a land command")
        assert fake.sent("land")[0].vehicle_id == "uav1"
        await until(pilot, lambda: app._fleet.cell_text("uav1", "state") == "landing", "landing")
        assert app._header.last_reply == "land: landing uav1"

    run_console(settings, scenario)
    token.undeclare()
    fake.close()


def test_emergency_stop_needs_confirmation(router: Any) -> None:
    settings, session = router
    fake = FakeOrchestrator(session, [], ["uav1"])

    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await until(pilot, lambda: app.model.orchestrator == "online", "the orchestrator")
        await pilot.press("e")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "a confirmation")
        await pilot.press("l", "a", "e")  # command keys do nothing behind the question
        assert isinstance(app.screen, ConfirmScreen) and len(app.screen_stack) == 2
        await pilot.press("n")
        await until(pilot, lambda: not isinstance(app.screen, ConfirmScreen), "the main screen")
        await pilot.press("e")
        await until(pilot, lambda: isinstance(app.screen, ConfirmScreen), "a confirmation")
        await pilot.press("y")
        await until(pilot, lambda: fake.sent("estop"), "an estop command")
        assert len(fake.sent("estop")) == 1  # the first, declined, one was never sent
        assert fake.sent("land") == []
        assert fake.sent("estop")[0].vehicle_id is None  # the whole fleet
        await until(pilot, lambda: "motors stopped" in app._header.last_reply, "the answer")

    run_console(settings, scenario)
    fake.close()


def test_a_lost_vehicle_and_a_vanished_orchestrator_stand_out(router: Any) -> None:
    settings, session = router
    fake = FakeOrchestrator(session, [_job("j-3", "queued", "川", queue_position=1)], ["uav1"])
    token = declare_token(session, KEYS.vehicle_alive("uav1"))

    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await until(pilot, lambda: app.model.orchestrator == "online", "the orchestrator")
        publish(session, KEYS.telemetry("uav1"), telemetry(0, error_m=0.08))
        await until(
            pilot,
            lambda: any("tracking error" in a for a in app._alerts.alerts),
            "a tracking-error alert",
        )
        token.undeclare()
        await until(pilot, lambda: app._fleet.cell_text("uav1", "state") == "lost", "uav1 lost")
        await until(pilot, lambda: "uav1 lost" in app._alerts.alerts, "a lost alert")
        assert app._alerts.has_class("-active")
        fake.token.undeclare()
        await until(pilot, lambda: app._header.orchestrator == "offline", "orchestrator gone")
        assert app.model.job("j-3") is not None  # the last known state stays on screen
        assert "orchestrator gone" in " ".join(app._alerts.alerts)
        asked = fake.snapshots
        fake.token = declare_token(session, KEYS.orchestrator_alive)  # back (e.g. restarted)
        await until(pilot, lambda: app._header.orchestrator == "online", "orchestrator back")
        await until(pilot, lambda: fake.snapshots > asked, "the show asked for again")

    run_console(settings, scenario)
    fake.close()


WALL_SETTINGS = ConsoleSettings(
    show_id=SHOW,
    boards=(
        BoardGeometry("b1"),
        BoardGeometry("wall1", center_m_enu=(3.0, 0.0, 1.5), orientation="vertical"),
    ),
    vehicles=(
        VehicleSpec("uav1", "quadrotor-brush", "b1", "board"),
        VehicleSpec("hexa1", "hexarotor-sponge", "wall1", "wall"),
    ),
    force_error_alert_n=1.0,
)


def wall_telemetry(i: int, force_n: float, target_n: float) -> Telemetry:
    """The hexarotor pressing its sponge on wall1 (x along the wall, z up)."""
    x = 2.8 + 0.01 * i
    return Telemetry(
        vehicle_id="hexa1",
        t_s=0.05 * i,
        state="writing",
        position_m_enu=(x, 0.0, 1.5),
        velocity_mps_enu=(0.2, 0.0, 0.0),
        reference_m_enu=(x, 0.0, 1.5),
        pen_down=True,
        tracking_error_m=0.002,
        job_id="j-3",
        progress=i / 60,
        force_n=force_n,
        force_reference_n=target_n,
    )


def test_the_wall_writers_force_shows_against_its_target_in_its_row_and_detail(
    router: Any,
) -> None:
    settings, session = router
    fake = FakeOrchestrator(session, [_job("j-3", "writing", "工", vehicle_id="hexa1")], [])
    token = declare_token(session, KEYS.vehicle_alive("hexa1"))

    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        await until(pilot, lambda: app.model.orchestrator == "online", "the orchestrator")
        # the target ramps 1 -> 5 N; the measurement lags it, too far only in the last samples
        for i in range(40):
            target = 1.0 + 0.1 * i
            publish(session, KEYS.telemetry("hexa1"), wall_telemetry(i, target - 0.3, target))
        await until(pilot, lambda: app.model.track("hexa1").count == 40, "40 samples")
        await until(pilot, lambda: app._fleet.cell_text("hexa1", "force") == "4.6/4.9N", "force")
        assert app._fleet.cell_text("hexa1", "surface") == "wall"
        assert app._fleet.cell_text("hexa1", "kind") == "hexarotor-sponge"
        assert app._fleet.cell_text("uav1", "surface") == "board"
        assert app._fleet.cell_text("uav1", "force") == "-"  # a brush senses no force
        assert not app.model.vehicle_row("hexa1", time.time()).force_off
        publish(session, KEYS.telemetry("hexa1"), wall_telemetry(40, 2.0, 5.0))
        await until(pilot, lambda: app._fleet.cell_text("hexa1", "force") == "2.0/5.0N", "3 N off")
        assert app.model.vehicle_row("hexa1", time.time()).force_off
        assert "hexa1 force 2.0 N, target 5.0 N" in [a.message for a in app.model.alerts()]

        app._fleet.cursor_row = 1
        await pilot.press("d")
        plot = await _shown_force_plot(app, pilot)
        console = Console(width=60, record=True, file=io.StringIO())
        console.print(app.screen.query_one("#detail-info", Static).content)
        info = console.export_text()
        assert "force        2.00 N, target 5.00 N" in info
        assert "writes on    wall" in info
        canvas = plot.canvas
        assert canvas is not None
        assert "5.5 N" in str(plot.border_title)  # 1.1 x the largest force
        # the last column: the target (5 N) drawn above the measurement (2 N), both on the plot
        x = canvas.width_dots - 1
        heights = {
            layer: [y for y in range(canvas.height_dots) if canvas.get(x, y, layer)]
            for layer in (TARGET, MEASURED)
        }
        assert heights[TARGET] and heights[MEASURED]
        assert min(heights[TARGET]) < min(heights[MEASURED])

    run_console(settings, scenario, WALL_SETTINGS)
    token.undeclare()
    fake.close()


async def _shown_force_plot(app: ConsoleApp, pilot: Any) -> ForcePlot:
    await until(pilot, lambda: app.screen.query(ForcePlot), "the vehicle's detail")
    plot = app.screen.query_one(ForcePlot)
    await until(pilot, lambda: plot.display and plot.canvas is not None, "the force plot")
    return plot


def test_a_brush_quadrotors_detail_has_no_force_plot(router: Any) -> None:
    settings, session = router
    fake = FakeOrchestrator(session, [_job("j-2", "writing", "一", vehicle_id="uav1")], ["uav1"])

    async def scenario(app: ConsoleApp, pilot: Any) -> None:
        for i in range(10):
            publish(session, KEYS.telemetry("uav1"), telemetry(i))
        await until(pilot, lambda: app.model.track("uav1").count == 10, "10 samples")
        await pilot.press("d")
        await until(pilot, lambda: app.screen.query(ForcePlot), "the vehicle's detail")
        await pilot.pause(0.3)
        assert not app.screen.query_one(ForcePlot).display

    run_console(settings, scenario)
    fake.close()
