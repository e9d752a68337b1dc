"""The fleet: one row per vehicle, a cursor to pick one, redrawn row by row.

A line-API widget rather than a DataTable: with a hundred vehicles whose numbers change several
times a second, only the rows that changed and are on screen are rendered again.
"""

from __future__ import annotations

from typing import ClassVar

from rich.cells import cell_len
from rich.segment import Segment
from rich.style import Style
from rich.text import Text
from textual.binding import Binding, BindingType
from textual.events import Click
from textual.geometry import Size
from textual.message import Message
from textual.reactive import reactive
from textual.scroll_view import ScrollView
from textual.strip import Strip

from tui import format as fmt
from tui.rows import VehicleRow

COLUMNS = (
    ("vehicle", "Vehicle"),
    ("surface", "On"),
    ("state", "State"),
    ("char", "Char"),
    ("progress", "Progress"),
    ("error", "Error"),
    ("force", "Force"),
    ("battery", "Batt"),
    ("preflight", "Pre"),
    ("age", "Link"),
    ("flown", "Flown"),
    ("job", "Job"),
    ("kind", "Kind"),
)
"""Column keys and headings; the most urgent first, so narrow terminals still show them. ``On``
says what the vehicle writes on (``board``, ``wall``, ``floor``), so a wall or ground writer reads
as one at once; ``Force`` is the contact force against its target (kinds that control force);
``Batt`` is the charge left and the minutes until empty; ``Pre`` its preflight (``ok``, or the
check that holds it: the detail screen has the reason); ``Link`` how long since it was heard and
the share of its autopilot's messages lost; ``Flown`` its time off the ground today. At 80
columns ``Kind``, ``Job`` and ``Flown`` drop first (``Link`` too when its text is long): the
detail screen (Enter) shows them all, with the preflight's whole reason."""
_COLUMN_INDEX = {key: i for i, (key, _) in enumerate(COLUMNS)}

Cell = tuple[str, str]
"""Text and style of one cell."""
Cells = tuple[Cell, ...]
GAP = 2
"""Spaces between columns."""
ID_CHARS = 24
"""Longest vehicle id or kind shown, in characters (bus strings: cleaned and cut)."""
_HEADER_STYLE = Style(bold=True)
_CURSOR_STYLE = Style(bgcolor="#0178d4", color="#ffffff")
_CURSOR_BLURRED_STYLE = Style(bgcolor="#3a3a3a")


def _cell(value: Text | str) -> Cell:
    if isinstance(value, Text):
        return value.plain, str(value.style or "")
    return value, ""


def row_cells(row: VehicleRow) -> Cells:
    """The cells of one vehicle, in column order; every bus string cleaned (see tui.safe_text)."""
    values: tuple[Text | str, ...] = (
        Text(fmt.short_id(row.vehicle_id, ID_CHARS), style="bold"),
        row.surface or "-",
        fmt.vehicle_state_text(row.state, row.held, row.paused),
        Text(fmt.short_id(row.job_label, 6) if row.job_label else "-", style="bold"),
        fmt.progress(row.progress, 5) if row.job_id else "",
        fmt.tracking_error(row),
        fmt.force(row),
        fmt.battery(row.battery_fraction, row.battery_minutes_left),
        fmt.preflight(row),
        fmt.link(row),
        fmt.duration(row.flight_s_today),
        fmt.short_id(row.job_id) if row.job_id else "-",
        fmt.short_id(row.kind, ID_CHARS) if row.kind else "-",
    )
    return tuple(_cell(v) for v in values)


class FleetTable(ScrollView, can_focus=True):
    """Vehicles in show-file order; arrows move the cursor, Enter opens the vehicle's detail."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("up", "cursor(-1)", "up", show=False),
        Binding("down", "cursor(1)", "down", show=False),
        Binding("pageup", "cursor(-10)", "page up", show=False),
        Binding("pagedown", "cursor(10)", "page down", show=False),
        Binding("home", "cursor(-1000000)", "first", show=False),
        Binding("end", "cursor(1000000)", "last", show=False),
        Binding("enter", "choose", "details", show=False),
    ]

    cursor_row: reactive[int] = reactive(0)
    """Index of the selected vehicle."""

    class VehicleChosen(Message):
        """The operator pressed Enter on a vehicle."""

        def __init__(self, vehicle_id: str) -> None:
            super().__init__()
            self.vehicle_id = vehicle_id

    def __init__(self, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self._order: list[str] = []
        self._cells: dict[str, Cells] = {}
        self._strips: dict[str, Strip] = {}
        self._widths = [cell_len(heading) for _, heading in COLUMNS]
        self._styles: dict[str, Style] = {"": Style()}

    # --- reading ---------------------------------------------------------------------------------
    @property
    def row_count(self) -> int:
        return len(self._order)

    @property
    def selected_vehicle(self) -> str | None:
        """Vehicle under the cursor."""
        return self._order[self.cursor_row] if self._order else None

    def cell_texts(self, vehicle_id: str) -> tuple[str, ...]:
        """What the row of ``vehicle_id`` shows, column by column (empty if not listed)."""
        return tuple(text for text, _ in self._cells.get(vehicle_id, ()))

    def cell_text(self, vehicle_id: str, column: str) -> str | None:
        """What the row of ``vehicle_id`` shows in the column keyed ``column`` (None if not
        listed)."""
        cells = self._cells.get(vehicle_id)
        return None if cells is None else cells[_COLUMN_INDEX[column]][0]

    # --- updating --------------------------------------------------------------------------------
    def show_rows(self, rows: list[VehicleRow]) -> None:
        """Bring the table in line with ``rows``; only changed rows are rendered again."""
        added = False
        for row in rows:
            vid = row.vehicle_id
            cells = row_cells(row)
            if vid not in self._cells:
                self._order.append(vid)
                added = True
            elif self._cells[vid] == cells:
                continue
            self._cells[vid] = cells
            self._strips.pop(vid, None)
            self._widen(cells)
            if not added:
                self.refresh_line(self._order.index(vid) + 1)
        if added:
            self.virtual_size = Size(self.scrollable_content_region.width, len(self._order) + 1)
            self.refresh()

    def _widen(self, cells: Cells) -> None:
        for i, (text, _) in enumerate(cells):
            if cell_len(text) > self._widths[i]:
                self._widths[i] = cell_len(text)
                self._strips.clear()
                self.refresh()

    # --- cursor ----------------------------------------------------------------------------------
    def validate_cursor_row(self, row: int) -> int:
        return max(0, min(row, len(self._order) - 1))

    def watch_cursor_row(self, old: int, new: int) -> None:
        for index in (old, new):
            if 0 <= index < len(self._order):
                self._strips.pop(self._order[index], None)
        visible = max(1, self.scrollable_content_region.height - 1)
        if new < self.scroll_y:
            self.scroll_to(y=new, animate=False)
        elif new >= self.scroll_y + visible:
            self.scroll_to(y=new - visible + 1, animate=False)
        self.refresh()

    def action_cursor(self, step: int) -> None:
        self.cursor_row = self.cursor_row + step

    def action_choose(self) -> None:
        if self.selected_vehicle is not None:
            self.post_message(self.VehicleChosen(self.selected_vehicle))

    def on_click(self, event: Click) -> None:
        index = int(self.scroll_y) + event.y - 1
        if 0 <= index < len(self._order):
            self.cursor_row = index
            if event.chain > 1:
                self.action_choose()

    def on_focus(self) -> None:
        self._restyle_cursor()

    def on_blur(self) -> None:
        self._restyle_cursor()

    def _restyle_cursor(self) -> None:
        if self._order:
            self._strips.pop(self._order[self.cursor_row], None)
        self.refresh()

    def on_resize(self) -> None:
        self._strips.clear()
        self.virtual_size = Size(self.scrollable_content_region.width, len(self._order) + 1)

    # --- rendering -------------------------------------------------------------------------------
    def _style(self, name: str) -> Style:
        style = self._styles.get(name)
        if style is None:
            style = self._styles[name] = Style.parse(name)
        return style

    def _strip(self, texts: Cells, base: Style, extra: Style | None) -> Strip:
        row_style = base + extra if extra is not None else base
        width = self.scrollable_content_region.width
        segments = [Segment(" ", row_style)]
        used = 1
        for (text, style), column_width in zip(texts, self._widths, strict=True):
            if used + column_width > width:
                break  # whole columns only: the rightmost are the least urgent
            segments.append(Segment(text, row_style + self._style(style)))
            segments.append(Segment(" " * (column_width - cell_len(text) + GAP), row_style))
            used += column_width + GAP
        return Strip(segments).adjust_cell_length(width, row_style)

    def render_line(self, y: int) -> Strip:
        base = self.rich_style
        if y == 0:
            header = tuple((heading, "") for _, heading in COLUMNS)
            return self._strip(header, base, _HEADER_STYLE)
        index = int(self.scroll_y) + y - 1
        if not 0 <= index < len(self._order):
            return Strip.blank(self.scrollable_content_region.width, base)
        vid = self._order[index]
        strip = self._strips.get(vid)
        if strip is None:
            extra = None
            if index == self.cursor_row:
                extra = _CURSOR_STYLE if self.has_focus else _CURSOR_BLURRED_STYLE
            strip = self._strips[vid] = self._strip(self._cells[vid], base, extra)
        return strip
