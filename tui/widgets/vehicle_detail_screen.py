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
from tui.settings import BoardGeometry
from tui.widgets.board_view import BoardView
from tui.widgets.event_log import EventLog


def detail_table(row: VehicleRow) -> Table:
    """Name/value pairs of one vehicle."""
    table = Table.grid(padding=(0, 1))
    table.add_column(style="dim", no_wrap=True)
    table.add_column(no_wrap=True)
    position = (
        "-"
        if row.position_m_enu is None
        else "({:+.2f}, {:+.2f}, {:+.2f}) m".format(*row.position_m_enu)
    )
    pairs: list[tuple[str, str | Text]] = [
        ("vehicle", Text(row.vehicle_id, style="bold")),
        ("kind", row.kind or "-"),
        ("state", fmt.state_text(row.state)),
        ("board", row.board_id or "-"),
        ("job", row.job_id or "-"),
        ("character", Text(row.job_label or "-", style="bold")),
        ("progress", fmt.progress(row.progress, 10)),
        ("tracking err", fmt.tracking_error(row)),
        ("battery", fmt.battery(row.battery_fraction)),
        ("link age", fmt.link_age(row)),
        ("position", position),
        ("message", row.message or "-"),
    ]
    for name, value in pairs:
        table.add_row(name, value)
    return table


class VehicleDetailScreen(Screen[None]):
    """One vehicle in full; Escape goes back, ``l`` lands it, ``e`` stops it (confirmed)."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("escape,q", "app.pop_screen", "back"),
        Binding("l", "land", "land it"),
        Binding("e", "estop", "E-STOP it"),
    ]

    class LandRequested(Message):
        def __init__(self, vehicle_id: str) -> None:
            super().__init__()
            self.vehicle_id = vehicle_id

    class EstopRequested(Message):
        def __init__(self, vehicle_id: str) -> None:
            super().__init__()
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
            yield BoardView(self.board, self.model, vehicle_id=self.vehicle_id, id="detail-board")
        with Vertical(id="detail-bottom"):
            yield EventLog(vehicle_id=self.vehicle_id, id="detail-log")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one("#detail-info").border_title = self.vehicle_id
        self.query_one(EventLog).border_title = f"events of {self.vehicle_id}"

    def sync(self, now_s: float) -> None:
        """Show the model's current state of the vehicle."""
        row = self.model.vehicle_row(self.vehicle_id, now_s)
        info = self.query_one("#detail-info", Static)
        info.update(detail_table(row) if row else Text(f"{self.vehicle_id}: unknown"))
        self.query_one(BoardView).sync(now_s)
        log = self.query_one(EventLog)
        log.add_events(self.model.events_after(log.last_seq))

    def action_land(self) -> None:
        self.post_message(self.LandRequested(self.vehicle_id))

    def action_estop(self) -> None:
        self.post_message(self.EstopRequested(self.vehicle_id))
