"""The venue seen from above, to scale: boards, walls, floor areas, homes, geofences, vehicles.

Pure: no Textual, no I/O. :func:`venue_from_show` takes what the console needs from the show
file (the same fences the agents enforce, :func:`showfile.geofence.show_fence_outline_xy_m`);
:func:`draw_venue` draws it with the vehicles where they are into a block of terminal cells:
outlines in braille (north up, one scale for both axes), each vehicle a label character
coloured by its state, a scale bar and a legend below. It fits 80x24 and grows with the screen.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

from rich.style import Style
from rich.text import Text

from showfile import Show
from showfile.checks import footprint
from showfile.geofence import show_fence_outline_xy_m
from tui.braille import BrailleCanvas, apply_transform, fit_transform
from tui.format import STATE_STYLES
from tui.safe_text import clean

Point2 = tuple[float, float]

FENCE, FLOOR, BOARD, WALL, HOME = range(5)
LAYER_STYLES = ("#5f5f00", "#875f00", "#8a8a8a", "#d7d7d7", "#00af00")
"""Style per layer: fence (dim olive), floor area, board (a table), wall, home."""
LEGEND = (
    ("┈fence", LAYER_STYLES[FENCE]),
    ("▭board", LAYER_STYLES[BOARD]),
    ("▭wall", LAYER_STYLES[WALL]),
    ("▭floor", LAYER_STYLES[FLOOR]),
    ("+home", LAYER_STYLES[HOME]),
)
SURFACE_LAYERS = {"horizontal": BOARD, "vertical": WALL, "floor": FLOOR}
LABELS = "123456789abcdefghijkmnopqrstuvwxyzABCDEFGHJKLMNPQRSTUVWXYZ"
"""Vehicle labels on the plan, in show-file order (more vehicles than labels share ``*``)."""
_SCALE_STEPS_M = (0.1, 0.2, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)
_HOME_ARM_M = 0.15
"""Half the span of a home's cross, in [m]."""


@dataclass(frozen=True)
class VenueArea:
    """A board, wall or floor area in plan view."""

    area_id: str
    orientation: str
    """``horizontal`` (a board), ``vertical`` (a wall) or ``floor``, as in the show file."""
    corners_xy_m: tuple[Point2, ...]
    """Plan-view corners in [m], world x (east) / y (north)."""


@dataclass(frozen=True)
class VenueVehicle:
    """A vehicle's fixed places: its home and its geofence."""

    vehicle_id: str
    home_xy_m: Point2
    """Take-off and landing point in [m], world x/y."""
    fence_xy_m: tuple[Point2, ...]
    """Its geofence's plan view in [m], world x/y, counter-clockwise."""


@dataclass(frozen=True)
class Venue:
    """Everything fixed on the plan."""

    areas: tuple[VenueArea, ...] = ()
    vehicles: tuple[VenueVehicle, ...] = ()

    def bounds_m(self) -> tuple[float, float, float, float]:
        """``(x_min, y_min, x_max, y_max)`` in [m] of every outline (a 1 m box when empty)."""
        points = [p for a in self.areas for p in a.corners_xy_m]
        points += [p for v in self.vehicles for p in (*v.fence_xy_m, v.home_xy_m)]
        if not points:
            return (-0.5, -0.5, 0.5, 0.5)
        xs, ys = [p[0] for p in points], [p[1] for p in points]
        return min(xs), min(ys), max(xs), max(ys)


@dataclass(frozen=True)
class VehicleMark:
    """Where a vehicle is now, as the console knows it."""

    vehicle_id: str
    state: str
    position_m_enu: tuple[float, float, float] | None
    """None before its first telemetry."""
    stale: bool = False


def venue_from_show(show: Show) -> Venue:
    """The plan of a loaded show."""
    areas = tuple(
        VenueArea(b.id, b.orientation, tuple(footprint(b))) for b in show.boards
    )  # fmt: skip
    vehicles = tuple(
        VenueVehicle(v.id, (v.home_m_enu[0], v.home_m_enu[1]), show_fence_outline_xy_m(show, v.id))
        for v in show.vehicles
    )
    return Venue(areas, vehicles)


def vehicle_label(index: int) -> str:
    """The label of the ``index``-th vehicle of the show."""
    return LABELS[index] if index < len(LABELS) else "*"


def draw_venue(venue: Venue, marks: Sequence[VehicleMark], cols: int, rows: int) -> Text:
    """The plan in ``cols`` x ``rows`` cells: the picture, a scale bar, a legend and one entry per
    vehicle (as many as fit; the last line says how many more)."""
    legend_rows = max(2, min(rows // 3, 1 + math.ceil(len(venue.vehicles) / _per_line(cols))))
    plan_rows = max(rows - legend_rows, 1)
    canvas = BrailleCanvas(cols, plan_rows, layers=len(LAYER_STYLES))
    transform = fit_transform(venue.bounds_m(), canvas.width_dots, canvas.height_dots)
    for vehicle in venue.vehicles:
        _polygon(canvas, transform, vehicle.fence_xy_m, FENCE, dashed=True)
    for area in venue.areas:
        _polygon(canvas, transform, area.corners_xy_m, SURFACE_LAYERS.get(area.orientation, BOARD))
    for vehicle in venue.vehicles:
        x, y = vehicle.home_xy_m
        for (xa, ya), (xb, yb) in (
            ((x - _HOME_ARM_M, y), (x + _HOME_ARM_M, y)),
            ((x, y - _HOME_ARM_M), (x, y + _HOME_ARM_M)),
        ):
            canvas.line(*_dot(transform, xa, ya), *_dot(transform, xb, yb), layer=HOME)
    cells = _cells(canvas)
    order = {v.vehicle_id: i for i, v in enumerate(venue.vehicles)}
    for mark in marks:
        if mark.position_m_enu is None or mark.vehicle_id not in order:
            continue
        dx, dy = apply_transform(transform, mark.position_m_enu[0], mark.position_m_enu[1])
        col, row = int(dx) >> 1, int(dy) >> 2
        if 0 <= col < cols and 0 <= row < plan_rows:
            cells[row][col] = (vehicle_label(order[mark.vehicle_id]), _mark_style(mark))
    text = Text(no_wrap=True, overflow="crop")
    for row_cells in cells:
        for char, style in row_cells:
            text.append(char, style)
        text.append("\n")
    text.append_text(_scale_and_legend(transform[0], cols))
    text.append_text(_roster(venue, marks, order, cols, legend_rows - 1))
    return text


def _dot(transform: tuple[float, float, float, bool], x_m: float, y_m: float) -> Point2:
    return apply_transform(transform, x_m, y_m)


def _polygon(
    canvas: BrailleCanvas,
    transform: tuple[float, float, float, bool],
    corners_xy_m: Sequence[Point2],
    layer: int,
    *,
    dashed: bool = False,
) -> None:
    if not corners_xy_m:
        return
    dots = [_dot(transform, x, y) for x, y in (*corners_xy_m, corners_xy_m[0])]
    if not dashed:
        canvas.polyline(dots, layer)
        return
    for (x0, y0), (x1, y1) in itertools.pairwise(dots):
        steps = max(1, round(math.hypot(x1 - x0, y1 - y0)))
        for i in range(0, steps + 1, 2):  # every other dot: a dotted line
            canvas.set(round(x0 + (x1 - x0) * i / steps), round(y0 + (y1 - y0) * i / steps), layer)


def _cells(canvas: BrailleCanvas) -> list[list[tuple[str, Style | str]]]:
    styles = [Style.parse(s) for s in LAYER_STYLES]
    out = []
    for r in range(canvas.rows):
        row = []
        for c in range(canvas.cols):
            char, layer = canvas.cell(c, r)
            row.append((char, "" if layer is None else styles[layer]))
        out.append(row)
    return out


def _mark_style(mark: VehicleMark) -> str:
    style = STATE_STYLES.get(mark.state, "")
    return "dim" if mark.stale else ("bold reverse " + style).strip()


def _scale_and_legend(dots_per_m: float, cols: int) -> Text:
    """``├──────┤ 1 m`` (a round length 4-16 cells long), then the legend, one line."""
    cells_per_m = dots_per_m / 2.0
    length_m = next((s for s in _SCALE_STEPS_M if s * cells_per_m >= 4), _SCALE_STEPS_M[-1])
    bar_cells = max(2, min(round(length_m * cells_per_m), cols // 3))
    text = Text(no_wrap=True, overflow="crop")
    text.append("├" + "─" * (bar_cells - 2) + "┤", "bold")
    text.append(f" {length_m:g} m  N↑ ")
    for label, style in LEGEND:
        text.append(" ")
        text.append(label, style)
    text.append("\n")
    return text


def _per_line(cols: int) -> int:
    return max(1, cols // 22)


def _roster(
    venue: Venue, marks: Sequence[VehicleMark], order: dict[str, int], cols: int, lines: int
) -> Text:
    """``1 uav1 writing`` per vehicle, several to a line; the last line notes any left out."""
    states = {m.vehicle_id: m for m in marks}
    entries = []
    for vehicle in venue.vehicles:
        mark = states.get(vehicle.vehicle_id)
        state = "unknown" if mark is None else mark.state
        entry = Text(no_wrap=True)
        entry.append(vehicle_label(order[vehicle.vehicle_id]), "bold")
        entry.append(" " + clean(vehicle.vehicle_id, 10) + " ")
        entry.append(clean(state.replace("_", " "), 8), STATE_STYLES.get(state, ""))
        entries.append(entry)
    per_line = _per_line(cols)
    width = cols // per_line
    capacity = max(lines, 0) * per_line
    shown = entries if len(entries) <= capacity else entries[: max(capacity - 1, 0)]
    text = Text(no_wrap=True, overflow="crop")
    for i, entry in enumerate(shown):
        entry.truncate(width - 1)
        text.append_text(entry)
        text.append(" " * (width - entry.cell_len))
        if (i + 1) % per_line == 0:
            text.append("\n")
    if len(shown) < len(entries):
        text.append(f"+{len(entries) - len(shown)} more (the fleet table lists all)", "dim")
    return text
