"""The operator console: the whole fleet and the queue on one screen, every command one key away.

Zenoh threads hand decoded messages to an :class:`~tui.inbox.Inbox` and wake the app with one
``post_message`` per batch; the app merges them into the pure :class:`~tui.model.ConsoleModel`
at once and redraws the views from it on a timer, at most ``redraw_hz`` times per second.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import ClassVar

from textual import work
from textual.app import App, ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.widgets import Footer

from bus.messages import CommandReply, ErrorInfo, OperatorCommand, Telemetry
from tui.inbox import Inbox
from tui.inputs import BusInput, OrchestratorPresence
from tui.link import ConsoleLink
from tui.model import ConsoleModel
from tui.settings import ConsoleSettings
from tui.throttle import RedrawThrottle
from tui.widgets.alert_bar import AlertBar
from tui.widgets.board_grid import BoardGrid
from tui.widgets.board_view import BoardView
from tui.widgets.confirm_screen import ConfirmScreen
from tui.widgets.event_log import EventLog
from tui.widgets.fleet_table import FleetTable
from tui.widgets.header_bar import HeaderBar
from tui.widgets.preview_pane import PreviewPane
from tui.widgets.queue_table import QueueTable
from tui.widgets.vehicle_detail_screen import VehicleDetailScreen

TABLE_HZ = 5.0
"""Highest update rate of the fleet table's numbers, in [Hz]."""


class ConsoleApp(App[None]):
    """``skyquill tui``: watches the show on the bus and sends operator commands."""

    CSS_PATH = "console.tcss"
    TITLE = "skyquill"
    ENABLE_COMMAND_PALETTE = False
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("a", "approve", "approve"),
        Binding("r", "reject", "reject"),
        Binding("p", "toggle_pause", "pause"),
        Binding("c", "cancel_job", "cancel"),
        Binding("l", "land", "land"),
        Binding("L", "land_all", "land all"),
        Binding("e", "estop", "E-STOP"),
        Binding("d", "detail", "detail", show=False),
        Binding("x", "acknowledge", "ack alerts", show=False),
        Binding("q", "quit", "quit", show=False),
    ]

    class BusWake(Message):
        """Messages wait in the inbox (posted from a Zenoh thread, once per batch)."""

    class CommandDone(Message):
        """The orchestrator answered (or did not answer) an operator command."""

        def __init__(self, command: OperatorCommand, reply: CommandReply) -> None:
            super().__init__()
            self.command = command
            self.reply = reply

    def __init__(
        self,
        settings: ConsoleSettings,
        *,
        link: ConsoleLink | None = None,
        model: ConsoleModel | None = None,
        clock: Callable[[], float] = time.time,
    ) -> None:
        super().__init__()
        self.settings = settings
        self.model = model or ConsoleModel(settings)
        """Everything known about the show; widgets draw from it."""
        self.link = link
        """The bus; None runs the console on :attr:`model` alone (tests, replays)."""
        self.clock = clock
        """Console time in [s] (Unix time by default); injected for reproducible screens."""
        self.inbox: Inbox[BusInput] = Inbox(lambda item: isinstance(item, Telemetry))
        self._tick_s = 1.0 / (2.0 * settings.redraw_hz)
        self.throttle = RedrawThrottle(settings.redraw_hz, slack_s=self._tick_s / 2)
        self.table_throttle = RedrawThrottle(
            min(settings.redraw_hz, TABLE_HZ), slack_s=self._tick_s / 2
        )
        """Numbers are unreadable above a few changes per second; paths are drawn faster."""
        self.frames = 0
        """Redraws done so far."""
        self.frame_time_s = 0.0
        """Time spent in the latest redraw, in [s]."""
        self._drawn: dict[str, int] = {}
        self._drawn_boards: tuple[int, int, int] | None = None
        self._alerted: set[str] = set()
        self._fleet = FleetTable(id="fleet")
        self._queue = QueueTable(id="queue")
        self._preview = PreviewPane(id="preview")
        self._boards = BoardGrid(id="boards")
        self._event_log = EventLog(id="log")
        self._header = HeaderBar(id="header")
        self._alerts = AlertBar(id="alerts")

    # --- layout ----------------------------------------------------------------------------------
    def compose(self) -> ComposeResult:
        yield self._header
        yield self._alerts
        with Vertical(id="main"):
            yield self._fleet
            with Horizontal(id="middle"):
                with self._boards:
                    for board in self.settings.boards:
                        yield BoardView(board, self.model, id=f"board-{board.board_id}")
                with Horizontal(id="queue-pane"):
                    yield self._queue
                    yield self._preview
            yield self._event_log
        yield Footer()

    def on_mount(self) -> None:
        self._header.show_id = self.settings.show_id
        self._fleet.border_title = "fleet"
        self._fleet.border_subtitle = "enter: details"
        self._queue.border_title = "queue"
        self._event_log.border_title = "events"
        self._fleet.focus()
        self.set_interval(self._tick_s, self._tick)
        if self.link is not None:
            self.link.start(self._deliver)
            self.join_show()
        self.redraw()

    def on_unmount(self) -> None:
        if self.link is not None:
            self.link.close()

    # --- from the bus ----------------------------------------------------------------------------
    def _deliver(self, item: BusInput) -> None:
        """Called on Zenoh's threads."""
        if self.inbox.put(item):
            self.post_message(self.BusWake())

    def on_console_app_bus_wake(self, _: BusWake) -> None:
        now_s = self.clock()
        for item in self.inbox.drain():
            self.model.apply(item, now_s)
            if isinstance(item, OrchestratorPresence) and item.alive:
                self.join_show()

    @work(exclusive=True, group="snapshot")
    async def join_show(self) -> None:
        """Late joiner: ask the orchestrator for the whole show, then follow live messages."""
        if self.link is None:
            return
        snapshot = await self.link.query_snapshot()
        now_s = self.clock()
        if snapshot is None:
            self.model.note(now_s, "warning", "console", "no snapshot from the orchestrator")
        else:
            self.model.apply_snapshot(snapshot, now_s, full=True)

    # --- redraw ----------------------------------------------------------------------------------
    def _tick(self) -> None:
        if self.throttle.due(time.monotonic(), self.model.version != self._drawn.get("all")):
            self.redraw()

    def redraw(self) -> None:
        """Bring every view in line with the model (only the parts that changed)."""
        start = time.perf_counter()
        now_s = self.clock()
        self._redraw_status()
        table_done = self._redraw_fleet(now_s)
        self._redraw_queue()
        self._redraw_boards(now_s)
        if self.model.event_seq != self._event_log.last_seq:
            self._event_log.add_events(self.model.events_after(self._event_log.last_seq))
        if isinstance(self.screen, VehicleDetailScreen):
            self.screen.sync(now_s)
        if table_done:  # else the next tick comes back for the table
            self._drawn["all"] = self.model.version
        self.frames += 1
        self.frame_time_s = time.perf_counter() - start

    def _redraw_status(self) -> None:
        m = self.model
        self._header.orchestrator = m.orchestrator
        self._header.queue_paused = m.queue_paused
        counts = m.state_counts()
        text = f"{sum(counts.values())} vehicles, {counts.get('writing', 0)} writing"
        self._header.counts = text + (f", {counts['lost']} lost" if counts.get("lost") else "")
        if m.last_reply is not None:
            command, reply = m.last_reply
            self._header.last_reply = f"{command.command}: {_reply_text(reply)}"
            self._header.last_reply_ok = reply.ok
        alerts = m.alerts()
        self._alerts.alerts = tuple(alert.message for alert in alerts)
        keys = {alert.key for alert in alerts}
        if keys - self._alerted:
            self.bell()  # a new alert: the operator may be looking elsewhere
        self._alerted = keys

    def _redraw_fleet(self, now_s: float) -> bool:
        """Update the fleet table if it is due; False when it changed but had to wait."""
        dirty = self._drawn.get("table") != self.model.fleet_version
        if not self.table_throttle.due(time.monotonic(), dirty):
            return not dirty
        self._drawn["table"] = self.model.fleet_version
        self._fleet.show_rows(self.model.vehicle_rows(now_s))
        return True

    def _redraw_queue(self) -> None:
        if self._drawn.get("queue") != self.model.queue_version:
            self._drawn["queue"] = self.model.queue_version
            self._queue.show_rows(self.model.queue_rows())
            self._preview.job = self.model.job(self._queue.selected_job)

    def _redraw_boards(self, now_s: float) -> None:
        m = self.model
        key = (m.tracks_version, m.fleet_version, round(self._boards.scroll_y))
        if self._drawn_boards != key:  # new samples, new states, or other boards scrolled in
            self._drawn_boards = key
            self._boards.sync(now_s)

    # --- selection -------------------------------------------------------------------------------
    def on_queue_table_job_highlighted(self, message: QueueTable.JobHighlighted) -> None:
        self._preview.job = self.model.job(message.job_id)

    def on_fleet_table_vehicle_chosen(self, message: FleetTable.VehicleChosen) -> None:
        self._open_detail(message.vehicle_id)

    def _open_detail(self, vehicle_id: str) -> None:
        row = self.model.vehicle_row(vehicle_id, self.clock())
        board = self.settings.board(row.board_id if row else None)
        self.push_screen(VehicleDetailScreen(vehicle_id, self.model, board))
        self.call_after_refresh(self.redraw)

    # --- commands --------------------------------------------------------------------------------
    def check_action(self, action: str, parameters: tuple[object, ...]) -> bool | None:
        """No command keys behind a confirmation; no main-screen selections in the detail view."""
        if isinstance(self.screen, ConfirmScreen):
            return action in ("quit",)
        if isinstance(self.screen, VehicleDetailScreen):
            return action in ("quit", "land_all", "estop")
        return True

    def action_approve(self) -> None:
        self._job_command("approve", ("awaiting_approval", "submitted"))

    def action_reject(self) -> None:
        self._job_command("reject", ("awaiting_approval", "submitted"))

    def action_cancel_job(self) -> None:
        self._job_command(
            "cancel", ("awaiting_approval", "submitted", "queued", "assigned", "writing")
        )

    def _job_command(self, command: str, allowed: tuple[str, ...]) -> None:
        job = self.model.job(self._queue.selected_job)
        if job is None or job.state not in allowed:
            what = "a submission awaiting approval" if command != "cancel" else "a job not finished"
            self.notify(f"{command}: select {what} in the queue", severity="warning")
            return
        reason = "by operator" if command in ("reject", "cancel") else ""
        self.send(OperatorCommand(command=command, job_id=job.job_id, reason=reason))  # type: ignore[arg-type]

    def action_toggle_pause(self) -> None:
        self.send(OperatorCommand(command="resume" if self.model.queue_paused else "pause"))

    def action_land(self) -> None:
        vehicle_id = self._fleet.selected_vehicle
        if vehicle_id is None:
            self.notify("land: no vehicle selected", severity="warning")
            return
        self.send(OperatorCommand(command="land", vehicle_id=vehicle_id))

    def action_land_all(self) -> None:
        self._confirm("Land ALL vehicles now?", OperatorCommand(command="land_all"), "Land all")

    def action_estop(self) -> None:
        self._confirm(
            "EMERGENCY STOP every vehicle?\nMotors stop: vehicles in the air will fall.",
            OperatorCommand(command="estop", reason="operator emergency stop"),
            "E-STOP",
        )

    def on_vehicle_detail_screen_land_requested(self, m: VehicleDetailScreen.LandRequested) -> None:
        self.send(OperatorCommand(command="land", vehicle_id=m.vehicle_id))

    def on_vehicle_detail_screen_estop_requested(
        self, m: VehicleDetailScreen.EstopRequested
    ) -> None:
        self._confirm(
            f"EMERGENCY STOP {m.vehicle_id}?\nIts motors stop: in the air it will fall.",
            OperatorCommand(command="estop", vehicle_id=m.vehicle_id, reason="operator"),
            "E-STOP",
        )

    def _confirm(self, question: str, command: OperatorCommand, label: str) -> None:
        def answered(yes: bool | None) -> None:
            if yes:
                self.send(command)
            else:
                self.notify(f"{command.command}: not sent")

        self.push_screen(ConfirmScreen(question, label), answered)

    def action_detail(self) -> None:
        vehicle_id = self._fleet.selected_vehicle
        if vehicle_id is not None:
            self._open_detail(vehicle_id)

    def action_acknowledge(self) -> None:
        count = self.model.acknowledge_alerts()
        self.notify(f"{count} alert(s) acknowledged")
        self.redraw()

    @work(group="commands")
    async def send(self, command: OperatorCommand) -> None:
        """Send a command to the orchestrator and show its answer."""
        if self.link is None:
            info = ErrorInfo(code="offline", message="console not connected to a show")
            reply = CommandReply(ok=False, error=info)
        else:
            reply = await self.link.send_command(command, self.settings.command_timeout_s)
        self.post_message(self.CommandDone(command, reply))

    def on_console_app_command_done(self, message: CommandDone) -> None:
        self.model.record_command(message.command, message.reply, self.clock())
        text = f"{message.command.command}: {_reply_text(message.reply)}"
        self.notify(text, severity="information" if message.reply.ok else "error")
        self.redraw()


def _reply_text(reply: CommandReply) -> str:
    if reply.error is not None:
        return f"{reply.message + ': ' if reply.message else ''}{reply.error.message}"
    return reply.message or ("ok" if reply.ok else "refused")
