"""The venue plan: every board, wall, floor area, home and geofence to scale, and each vehicle
where it is now, coloured by its state (``m`` in the console; Escape or q goes back)."""

from __future__ import annotations

from typing import ClassVar

from rich.text import Text
from textual.app import ComposeResult
from textual.binding import Binding, BindingType
from textual.screen import Screen
from textual.widget import Widget
from textual.widgets import Footer

from tui.model import ConsoleModel
from tui.venue import VehicleMark, Venue, draw_venue


class VenueView(Widget):
    """The plan, drawn to the widget's size from the model's latest positions."""

    def __init__(self, venue: Venue, model: ConsoleModel, *, id: str | None = None) -> None:
        super().__init__(id=id)
        self.venue = venue
        self.model = model
        self._marks: list[VehicleMark] = []

    def sync(self, now_s: float) -> None:
        """Take the vehicles' positions and states from the model and redraw."""
        self._marks = [
            VehicleMark(row.vehicle_id, row.state, row.position_m_enu, row.stale)
            for row in self.model.vehicle_rows(now_s)
        ]
        self.refresh()

    def render(self) -> Text:
        cols, rows = self.content_size.width, self.content_size.height
        if cols < 10 or rows < 4:
            return Text("the window is too small for the venue plan")
        return draw_venue(self.venue, self._marks, cols, rows)


class VenueScreen(Screen[None]):
    """The whole venue from above; the app keeps it current while it is on top."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape,q,m", "back", "back")]

    def __init__(self, venue: Venue, model: ConsoleModel) -> None:
        super().__init__()
        self.venue = venue
        self.model = model

    def compose(self) -> ComposeResult:
        yield VenueView(self.venue, self.model, id="venue-plan")
        yield Footer()

    def on_mount(self) -> None:
        self.query_one(VenueView).border_title = Text("venue plan, seen from above")

    def sync(self, now_s: float) -> None:
        """Redraw with the model's state (nothing while composing or torn down)."""
        view = (
            next(iter(self.query(VenueView).results(VenueView)), None) if self.is_mounted else None
        )
        if view is not None:
            view.sync(now_s)

    def action_back(self) -> None:
        self.dismiss()
