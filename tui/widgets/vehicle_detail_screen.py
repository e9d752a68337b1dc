"""Everything about one vehicle: its numbers, its path on its board, its events."""

from __future__ import annotations

from typing import ClassVar

from rich.table import Table
from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.containers import Horizontal, Vertical
from textual.message import Message
from textual.screen import Screen
from textual.widgets import Footer, Static

from tui import format as fmt
from tui.model import ConsoleModel
from tui.rows import VehicleRow
from tui.safe_text import clean, plain
from tui.settings import BoardGeometry
from tui.widgets.board_view import BoardView
from tui.widgets.event_log import EventLog
from tui.widgets.force_plot import ForcePlot


def detail_table(row: VehicleRow) -> Table:
    """Name/value pairs of one vehicle; values are Text (a ``str`` cell would be read as markup)."""
    table = Table.grid(padding=(0, 1))
    table.add_column(style="dim", no_wrap=True)
    table.add_column(no_wrap=True)
    position = (
        "-"
        if row.position_m_enu is None
        else "({:+.2f}, {:+.2f}, {:+.2f}) m".format(*row.position_m_enu)
    )
    pairs: list[tuple[str, Text]] = [
        ("vehicle", plain(row.vehicle_id, "bold")),
        ("kind", plain(row.kind or "-")),
        ("writes on", plain(row.surface or "-")),
        ("state", fmt.vehicle_state_text(row.state, row.held, row.paused)),
        ("board", plain(row.board_id or "-")),
        ("job", plain(row.job_id or "-")),
        ("character", plain(row.job_label or "-", "bold")),
        ("progress", Text(fmt.progress(row.progress, 10))),
        ("tracking err", fmt.tracking_error(row)),
        ("force", fmt.force_detail(row)),
        ("battery", fmt.battery(row.battery_fraction, row.battery_minutes_left)),
        ("preflight", fmt.preflight(row, full=True)),
        ("link", fmt.link(row)),
        ("flown today", Text(fmt.duration(row.flight_s_today))),
        ("position", Text(position)),
        ("message", plain(row.message or "-")),
    ]
    for name, value in pairs:
        table.add_row(Text(name), value)
    return table


class VehicleDetailScreen(Screen[None]):
    """One vehicle in full; Escape or q goes back; its own commands are confirmed by the app."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape,q", "back", "back"),
        Binding("l", "request('land')", "land it"),
        Binding("u", "request('release')", "release it"),
        Binding("f", "request('clear_fault')", "reset fault"),
        Binding("e", "request('estop')", "E-STOP it"),
    ]

    class Requested(Message):
        """The operator asked for a command on this vehicle (the app confirms and sends it)."""

        def __init__(self, command: str, vehicle_id: str) -> None:
            super().__init__()
            self.command = command
            """``land``, ``release``, ``clear_fault`` or ``estop``."""
            self.vehicle_id = vehicle_id

    def __init__(self, vehicle_id: str, model: ConsoleModel, board: BoardGeometry | None) -> None:
        super().__init__()
        self.vehicle_id = vehicle_id
        """The vehicle shown."""
        self.model = model
        self.board = board or BoardGeometry(board_id="(no board)")

    def compose(self) -> ComposeResult:
        with Horizontal(id="detail-top"):
            yield Static(id="detail-info")
            with Vertical(id="detail-pictures"):
                yield BoardView(
                    self.board, self.model, vehicle_id=self.vehicle_id, id="detail-board"
                )
                yield ForcePlot(self.model, self.vehicle_id, id="detail-force")
        with Vertical(id="detail-bottom"):
            yield EventLog(vehicle_id=self.vehicle_id, id="detail-log")
        yield Footer()

    def on_mount(self) -> None:
        shown = clean(self.vehicle_id, 40)
        self.query_one("#detail-info").border_title = Text(shown)  # a str would be markup
        self.query_one(EventLog).border_title = Text(f"events of {shown}")

    def sync(self, now_s: float) -> None:
        """Show the model's state of the vehicle (nothing while it is being composed, or torn
        down with the app: mounted, its children gone)."""
        if not self.is_mounted:
            return
        info = next(self.query("#detail-info").results(Static), None)
        if info is None:
            return
        row = self.model.vehicle_row(self.vehicle_id, now_s)
        info.update(detail_table(row) if row else plain(f"{self.vehicle_id}: unknown"))
        self.query_one(BoardView).sync(now_s)
        self.query_one(ForcePlot).sync()
        log = self.query_one(EventLog)
        log.add_events(self.model.events.after(log.last_seq))

    def action_back(self) -> None:
        self.dismiss()

    def action_request(self, command: str) -> None:
        self.post_message(self.Requested(command, self.vehicle_id))
