"""The operator console: the whole fleet and the queue on one screen, every command one key away.

Zenoh threads hand decoded messages to an :class:`~tui.inbox.Inbox` and wake the app with one
``post_message`` per batch; the app merges them into the pure :class:`~tui.model.ConsoleModel`
at once and redraws the views from it (:mod:`tui.redraw`) on a timer, at most ``redraw_hz`` times
per second. Which key runs which action, and when, is :mod:`tui.keymap`'s.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import ClassVar

import msgspec
from textual import work
from textual.app import App, ComposeResult
from textual.binding import BindingType
from textual.containers import Horizontal, Vertical
from textual.events import Resize
from textual.message import Message
from textual.widgets import Footer

from bus.messages import CommandReply, ErrorInfo, JobState, OperatorCommand, Telemetry
from tui import commands as cmd
from tui.inbox import Inbox
from tui.inputs import BusInput, OrchestratorPresence
from tui.joining import ShowJoiner
from tui.keymap import KEYS, Focus, acts_now
from tui.link import ConsoleLink
from tui.model import ConsoleModel
from tui.redraw import Redrawer, answer_text
from tui.safe_text import clean
from tui.settings import ConsoleSettings
from tui.throttle import RedrawThrottle
from tui.widgets.alert_bar import AlertBar
from tui.widgets.board_grid import BoardGrid
from tui.widgets.board_strip import BoardStrip
from tui.widgets.board_view import BoardView
from tui.widgets.confirm_screen import ConfirmScreen
from tui.widgets.event_log import EventLog
from tui.widgets.fleet_table import FleetTable
from tui.widgets.header_bar import HeaderBar
from tui.widgets.help_screen import HelpScreen
from tui.widgets.preview_pane import PreviewPane
from tui.widgets.preview_screen import PreviewScreen
from tui.widgets.queue_table import QueueTable
from tui.widgets.vehicle_detail_screen import VehicleDetailScreen
from tui.widgets.venue_screen import VenueScreen

PREVIEW_MIN_WIDTH = 100
"""Narrowest terminal, in cells, that shows the small preview next to the queue."""


class ConsoleApp(App[None]):
    """``skyquill tui``: watches the show on the bus and sends operator commands."""

    CSS_PATH = "console.tcss"
    TITLE = "skyquill"
    ENABLE_COMMAND_PALETTE = False
    BINDINGS: ClassVar[list[BindingType]] = KEYS

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
        self.frames = 0
        """Redraws done so far."""
        self.frame_time_s = 0.0
        """Time spent in the latest redraw, in [s]."""
        self._joiner = ShowJoiner(link, self.model, clock) if link is not None else None
        self._fleet = FleetTable(id="fleet")
        self._queue = QueueTable(id="queue")
        self._preview = PreviewPane(id="preview")
        self._boards = BoardGrid(id="boards")
        self._event_log = EventLog(id="log")
        self._header = HeaderBar(id="header")
        self._alerts = AlertBar(id="alerts")
        self._strip = BoardStrip(self.model, settings, id="board-strip")
        self._queue_pane = Horizontal(id="queue-pane")
        self._redrawer = Redrawer(
            self.model,
            redraw_hz=settings.redraw_hz,
            slack_s=self._tick_s / 2,
            bell=self.bell,
            header=self._header,
            alerts=self._alerts,
            fleet=self._fleet,
            strip=self._strip,
            boards=self._boards,
            queue=self._queue,
            preview=self._preview,
            event_log=self._event_log,
        )

    # --- layout ----------------------------------------------------------------------------------
    def compose(self) -> ComposeResult:
        yield self._header
        yield self._alerts
        with Vertical(id="main"):
            yield self._fleet
            yield self._strip
            with Horizontal(id="middle"):
                with self._boards:
                    for board in self.settings.boards:
                        yield BoardView(board, self.model, id=f"board-{board.board_id}")
                with self._queue_pane:
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
            was_online = self.model.orchestrator == "online"
            self.model.apply(item, now_s)
            if isinstance(item, OrchestratorPresence) and item.alive and not was_online:
                self.join_show()  # once per appearance: Zenoh may announce a token twice
        if self.model.ended_unheard and self._joiner is not None and not self._joiner.asking:
            self.join_show()  # a job's final message was lost: the snapshot has its end

    @work(exclusive=True, group="snapshot")
    async def join_show(self) -> None:
        """Late joiner: ask the orchestrator for the whole show until it answers
        (:mod:`tui.joining`), then follow live messages. A new appearance of the orchestrator
        asks afresh (``exclusive``: the asking before it is cancelled)."""
        if self._joiner is not None:
            await self._joiner.join()

    # --- redraw ----------------------------------------------------------------------------------
    def _tick(self) -> None:
        if self.throttle.due(time.monotonic(), self._redrawer.stale):
            self.redraw()

    def redraw(self) -> None:
        """Bring every view in line with the model (only the parts that changed)."""
        start = time.perf_counter()
        now_s = self.clock()
        self._redrawer.redraw(now_s)
        stack = self.screen_stack  # empty while the app is being torn down
        if stack and isinstance(stack[-1], VehicleDetailScreen | VenueScreen):
            stack[-1].sync(now_s)
        self.frames += 1
        self.frame_time_s = time.perf_counter() - start

    def on_board_grid_relaid(self, message: BoardGrid.Relaid) -> None:
        self._redrawer.show_strip(not message.all_visible, self.clock())

    def on_resize(self, event: Resize) -> None:
        """Narrow terminals give the queue the preview's columns (``v`` shows it full-screen)."""
        width, height = event.size
        self._preview.display = width >= PREVIEW_MIN_WIDTH
        wide = width >= 160
        self._preview.styles.width = 30 if wide else 12
        self._queue_pane.styles.max_width = 104 if wide else 72
        self._event_log.styles.max_height = 12 if height < 40 else height // 4
        self._redrawer.forget_boards()

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
        """Only the keys that act now (:func:`tui.keymap.acts_now`); False also hides the key in
        the footer."""
        screen, focused = self.screen, self.focused
        focus: Focus = (
            "queue" if focused is self._queue else "fleet" if focused is self._fleet else None
        )
        return acts_now(action, screen, len(self.screen_stack), focus)

    def on_descendant_focus(self) -> None:
        self.refresh_bindings()

    def action_approve(self) -> None:
        job = self._selected_job()
        self._request(cmd.job_request("approve", job, self.model.phrase_of(job)))

    def action_reject(self) -> None:
        job = self._selected_job()
        self._request(cmd.job_request("reject", job, self.model.phrase_of(job)))

    def action_cancel_job(self) -> None:
        job = self._selected_job()
        self._request(cmd.job_request("cancel", job, self.model.phrase_of(job)))

    def action_mark(self, whole_client: bool = False) -> None:
        """Mark the selected job, or every waiting job of its client, for ``R``."""
        note = self._queue.mark_client() if whole_client else self._queue.toggle_mark()
        if note is not None:
            self.notify(note, markup=False)

    def action_reject_marked(self) -> None:
        self._request(cmd.bulk_request(self._queue.marked_jobs()))

    def action_priority(self, direction: str) -> None:
        self._request(cmd.job_request(direction, self._selected_job()))

    def action_preview(self) -> None:
        job = self._selected_job()
        if job is None:
            self.notify("preview: no job selected", severity="warning", markup=False)
        else:
            self.push_screen(PreviewScreen(job))

    def _selected_job(self) -> JobState | None:
        return self.model.job(self._queue.selected_job)

    def action_toggle_pause(self) -> None:
        self.send(OperatorCommand(command="resume" if self.model.queue_paused else "pause"))

    def action_vehicle(self, command: str, vehicle_id: str | None = None) -> None:
        """``land``, ``release``, ``clear_fault``, ``pause`` or ``battery_swapped`` of the
        selected (or the named) vehicle."""
        vid = vehicle_id or self._fleet.selected_vehicle
        row = self.model.vehicle_row(vid, self.clock()) if vid else None
        self._request(cmd.vehicle_request(command, row))

    def action_fresh_sheet(self) -> None:
        vid = self._fleet.selected_vehicle
        row = self.model.vehicle_row(vid, self.clock()) if vid else None
        self._request(cmd.fresh_sheet_request(row, self.model.dirty_boards))

    def action_clear_all(self) -> None:
        self._request(cmd.clear_all_request(self.model.fault_ids()))

    def action_release_all(self) -> None:
        self._request(cmd.release_all_request(self.model.held_ids(), self.model.queue_paused))

    def action_land_all(self) -> None:
        self._request(cmd.LAND_ALL)

    def action_estop(self, vehicle_id: str | None = None) -> None:
        self._request(cmd.estop_ask(vehicle_id))

    def on_vehicle_detail_screen_requested(self, m: VehicleDetailScreen.Requested) -> None:
        if m.command == "estop":
            self.action_estop(m.vehicle_id)
        else:
            self.action_vehicle(m.command, m.vehicle_id)

    def _request(self, request: cmd.Request) -> None:
        """Send, ask first, or say why not."""
        if isinstance(request, cmd.Refusal):
            self.notify(request.message, severity="warning", markup=False)
        elif isinstance(request, OperatorCommand):
            self.send(request)
        else:
            self._confirm(request)

    def _confirm(self, ask: cmd.Ask) -> None:
        def answered(reason: str | None) -> None:
            if reason is None:
                if ask.commands:
                    self.notify(f"{ask.commands[0].command}: not sent", markup=False)
            elif not ask.commands:
                self.exit()
            for command in ask.commands if reason is not None else ():
                self.send(msgspec.structs.replace(command, reason=reason or command.reason))

        screen = ConfirmScreen(ask.question, ask.label, reason_prompt=ask.reason_prompt)
        self.push_screen(screen, answered)

    async def action_quit(self) -> None:
        """Quit; while vehicles fly, only once the operator confirms (the show goes on)."""
        ask = cmd.quit_request(self.model.airborne_count())
        if ask is None:
            self.exit()
        else:
            self._confirm(ask)

    def action_help(self) -> None:
        if not isinstance(self.screen, HelpScreen):
            self.push_screen(HelpScreen())

    def action_detail(self) -> None:
        vehicle_id = self._fleet.selected_vehicle
        if vehicle_id is not None:
            self._open_detail(vehicle_id)

    def action_venue(self) -> None:
        self.push_screen(VenueScreen(self.settings.venue, self.model))
        self.redraw()

    def action_acknowledge(self) -> None:
        count = self.model.acknowledge_alerts()
        self.notify(f"{count} alert(s) acknowledged", markup=False)
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
        text = clean(answer_text(message.command, message.reply))
        self.notify(  # the answer may quote bus data
            text, severity="information" if message.reply.ok else "error", markup=False
        )
        self.redraw()
