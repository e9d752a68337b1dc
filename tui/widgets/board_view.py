"""One board: the character being written, reference and flown paths, drawn live in braille."""

from __future__ import annotations

from dataclasses import dataclass

from rich.segment import Segment
from rich.style import Style
from rich.text import Text
from textual.dom import NoScreen
from textual.errors import NoWidget
from textual.geometry import Region
from textual.reactive import reactive
from textual.strip import Strip
from textual.widget import Widget

from tui.braille import BrailleCanvas, apply_transform, fit_transform
from tui.model import ConsoleModel
from tui.safe_text import clean
from tui.settings import BoardGeometry
from tui.tracks import Track, TrackPoint

FRAME, FLOWN_UP, REFERENCE, INK, VEHICLE = range(5)
LAYER_STYLES = ("#4e4e4e", "#8a8a8a", "#0087ff", "bold #ffffff", "bold #ff3030")
_RICH_STYLES = tuple(Style.parse(style) for style in LAYER_STYLES)
"""Style per layer: writing-area corners, pen-up flight, reference (pen down), ink, vehicle."""
LEGEND = "[bold #ffffff]━ink[/] [#8a8a8a]┈pen-up[/] [#0087ff]━ref[/] [#ff3030]●[/]"
"""The board's subtitle: the console's own markup (no bus data)."""
TITLE_ID_CHARS = 24
TITLE_LABEL_CHARS = 16
"""Longest board/vehicle id and job label in a board's title, in characters."""


@dataclass
class _Drawn:
    generation: int
    count: int


class BoardView(Widget):
    """Paths of the vehicles on one board (or of one vehicle), redrawn incrementally."""

    title: reactive[str] = reactive("")

    def __init__(
        self,
        board: BoardGeometry,
        model: ConsoleModel,
        *,
        vehicle_id: str | None = None,
        **kwargs: object,
    ) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.board = board
        """The board drawn."""
        self.model = model
        self.vehicle_id = vehicle_id
        """Draw only this vehicle (detail view); all vehicles of the board when None."""
        self._canvas: BrailleCanvas | None = None
        self._transform: tuple[float, float, float, bool] | None = None
        self._drawn: dict[str, _Drawn] = {}
        self._markers: list[tuple[int, int]] = []
        self._canvas_synced: BrailleCanvas | None = None
        self._strips: list[Strip | None] = []
        self.border_subtitle = LEGEND

    def watch_title(self, title: str) -> None:
        self.border_title = Text(title)  # a str would be read as markup

    def _vehicles(self) -> list[str]:
        if self.vehicle_id is not None:
            return [self.vehicle_id]
        return self.model.vehicles_on_board(self.board.board_id)

    def on_show(self) -> None:
        self.sync(0.0)

    def in_view(self) -> bool:
        """Whether any of the board is on screen now (not scrolled away, not on a hidden screen)."""
        try:
            return bool(self.screen.find_widget(self).visible_region)
        except (NoScreen, NoWidget):
            return False

    def sync(self, now_s: float) -> None:
        """Draw what arrived since the last call; refresh only if something changed.

        A board scrolled out of view does nothing: it catches up when it is shown again.
        """
        if not self.in_view():
            return
        vehicles = self._vehicles()
        self.title = self._title(vehicles, now_s)
        fresh = self._canvas is None
        canvas = self._ensure_canvas()
        if canvas is None:
            return
        whole = fresh or canvas is not self._canvas_synced
        self._canvas_synced = canvas
        for vid in vehicles:
            track = self.model.track(vid)
            if track is not None:
                self._draw_new(canvas, vid, track)
        self._draw_vehicles(canvas, vehicles)
        if not (whole or canvas.dirty_rows):
            return
        for row in canvas.dirty_rows:
            self._strips[row] = None
        regions = [Region(0, row, canvas.cols, 1) for row in sorted(canvas.dirty_rows)]
        canvas.dirty_rows.clear()
        if whole:
            self.refresh()
        else:
            self.refresh(*regions)  # only the rows that changed: borders are costly to redraw

    def _title(self, vehicles: list[str], now_s: float) -> str:
        """Board, vehicles and what they write, as plain text (bus strings cleaned)."""
        parts = [clean(self.board.board_id, TITLE_ID_CHARS)]
        for vehicle_id in vehicles:
            row = self.model.vehicle_row(vehicle_id, now_s)
            if row is None:
                continue
            vid = clean(vehicle_id, TITLE_ID_CHARS)
            if row.job_label:
                label = clean(row.job_label, TITLE_LABEL_CHARS)
                parts.append(f"{vid} «{label}» {100 * row.progress:.0f}%")
                continue
            track = self.model.track(vehicle_id)
            last = self.model.job(track.job_id if track else None)
            if last is None:
                parts.append(vid)
            else:
                parts.append(f"{vid} (last «{clean(last.label, TITLE_LABEL_CHARS)}» {last.state})")
        if self.board.board_id in self.model.dirty_boards:
            parts.append("HALF-WRITTEN: new sheet, then s")
        return " · ".join(parts)

    def _ensure_canvas(self) -> BrailleCanvas | None:
        cols, rows = self.content_size.width, self.content_size.height
        if cols < 1 or rows < 1:
            return None
        canvas = self._canvas
        if canvas is not None and (canvas.cols, canvas.rows) == (cols, rows):
            return canvas
        canvas = self._canvas = BrailleCanvas(cols, rows, layers=len(LAYER_STYLES))
        self._strips = [None] * rows
        half_w, half_h = self.board.writing_area_m[0] / 2, self.board.writing_area_m[1] / 2
        self._transform = fit_transform(
            (-half_w, -half_h, half_w, half_h), canvas.width_dots, canvas.height_dots, margin_dots=0
        )
        self._drawn.clear()
        self._markers = []
        self._draw_frame(canvas)
        return canvas

    def _dot(self, position_m_enu: tuple[float, float, float]) -> tuple[float, float]:
        assert self._transform is not None
        u, v = self.board.to_board(position_m_enu)
        return apply_transform(self._transform, u, v)

    def _draw_frame(self, canvas: BrailleCanvas) -> None:
        assert self._transform is not None
        w, h = self.board.writing_area_m[0] / 2, self.board.writing_area_m[1] / 2
        tick = 0.08 * min(w, h)
        for sx in (-1.0, 1.0):
            for sy in (-1.0, 1.0):
                corner = apply_transform(self._transform, sx * w, sy * h)
                along_x = apply_transform(self._transform, sx * (w - tick), sy * h)
                along_y = apply_transform(self._transform, sx * w, sy * (h - tick))
                canvas.line(*corner, *along_x, layer=FRAME)
                canvas.line(*corner, *along_y, layer=FRAME)

    def _draw_new(self, canvas: BrailleCanvas, vid: str, track: Track) -> bool:
        drawn = self._drawn.get(vid)
        if drawn is None:
            drawn = self._drawn[vid] = _Drawn(track.generation, 0)
        elif drawn.generation != track.generation:  # a new job: the old path must go
            self._redraw_all(canvas)
            return True
        if drawn.count == track.count:
            return False
        points = track.points
        previous: TrackPoint | None = points[drawn.count - 1] if drawn.count else None
        for point in points[drawn.count : track.count]:
            self._segment(canvas, previous, point)
            previous = point
        drawn.count = track.count
        return True

    def _segment(self, canvas: BrailleCanvas, a: TrackPoint | None, b: TrackPoint) -> None:
        end = self._dot(b.position_m_enu)
        start = end if a is None else self._dot(a.position_m_enu)
        if b.pen_down and b.reference_m_enu is not None:
            ref_end = self._dot(b.reference_m_enu)
            ref_start = ref_end
            if a is not None and a.reference_m_enu is not None:
                ref_start = self._dot(a.reference_m_enu)
            canvas.line(*ref_start, *ref_end, layer=REFERENCE)
        canvas.line(*start, *end, layer=INK if b.pen_down else FLOWN_UP)

    def _redraw_all(self, canvas: BrailleCanvas) -> None:
        canvas.clear()
        self._drawn.clear()
        self._markers = []
        self._draw_frame(canvas)
        for vid in self._vehicles():
            track = self.model.track(vid)
            if track is not None:
                self._drawn[vid] = _Drawn(track.generation, 0)
                self._draw_new(canvas, vid, track)

    def _draw_vehicles(self, canvas: BrailleCanvas, vehicles: list[str]) -> bool:
        """Mark where each flying vehicle is now; True when a mark moved."""
        markers: list[tuple[int, int]] = []
        for vid in vehicles:
            row = self.model.vehicle_row(vid, 0.0)
            if row is None or row.position_m_enu is None or row.state in ("lost", "landed"):
                continue
            x, y = self._dot(row.position_m_enu)
            markers.append((round(x), round(y)))
        if markers == self._markers:
            return False
        canvas.clear_layer(VEHICLE)
        for x, y in markers:
            canvas.set(x, y, VEHICLE)
        self._markers = markers
        return True

    def render_line(self, y: int) -> Strip:
        canvas = self._canvas
        if canvas is None or not 0 <= y < canvas.rows:
            return Strip.blank(self.content_size.width, self.rich_style)
        strip = self._strips[y]
        if strip is None:
            base = self.rich_style
            strip = Strip(
                [
                    Segment(chars, base if layer is None else base + _RICH_STYLES[layer])
                    for chars, layer in canvas.row_runs(y)
                ],
                canvas.cols,
            )
            self._strips[y] = strip
        return strip

    def on_resize(self) -> None:
        self.sync(0.0)  # a new size means a new canvas, drawn again from the tracks
