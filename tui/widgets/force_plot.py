"""A vehicle's contact force against its target over the current job, drawn in braille.

Only kinds that control force send it (the hexarotor on its wall); for the others the plot says
so in one line. Redrawn only when the track grew or restarted.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from rich.text import Text
from textual.widgets import Static

from tui.braille import BrailleCanvas
from tui.model import ConsoleModel
from tui.tracks import TrackPoint

TARGET, MEASURED = range(2)
PLOT_STYLES = ("#0087ff", "bold #ffffff")
"""Style per layer: the target force, the measured force (drawn over it)."""
LEGEND = "[bold #ffffff]━measured[/] [#0087ff]━target[/]"
"""The plot's subtitle: the console's own markup (no bus data)."""
TOP_MAX_N = 1000.0
"""Highest force the plot's scale reaches in [N]; larger values (bus data) are drawn at the top."""
NO_FORCE = "no contact force in this job's telemetry"


def force_series(
    points: Sequence[TrackPoint], columns: int
) -> tuple[list[float | None], list[float | None]]:
    """Measured and target force in [N], one value per plot column (the last sample falling in
    it, so fewer samples than columns are stretched), over the whole track; None where the
    vehicle sent none."""
    count = len(points)
    measured: list[float | None] = []
    target: list[float | None] = []
    for c in range(columns):
        i = -(-(c + 1) * count // columns) - 1  # ceil: the newest sample in the column
        point = points[i] if i >= 0 else None
        measured.append(None if point is None else point.force_n)
        target.append(None if point is None else point.force_reference_n)
    return measured, target


def plot_force(
    measured: Sequence[float | None], target: Sequence[float | None], cols: int, rows: int
) -> tuple[BrailleCanvas, float]:
    """A canvas of both series (one value per dot column, 0 N at the bottom) and the force in
    [N] at its top (the largest value plus a tenth, at least 1 N). A value that is not a finite
    number (bus data) is left out like a missing one."""
    canvas = BrailleCanvas(cols, rows, layers=len(PLOT_STYLES))
    measured, target = _finite(measured), _finite(target)
    values = [v for v in (*measured, *target) if v is not None]
    top_n = min(TOP_MAX_N, max(1.0, 1.1 * max(values, default=0.0)))
    bottom = canvas.height_dots - 1
    for layer, series in ((TARGET, target), (MEASURED, measured)):
        previous: int | None = None
        for x, value in enumerate(series[: canvas.width_dots]):
            if value is None:
                previous = None
                continue
            y = round(bottom - bottom * min(max(value, 0.0), top_n) / top_n)
            # a step from the previous column is a run of dots in this one (a line, cheaply)
            low, high = (y, y) if previous is None else (min(previous, y), max(previous, y))
            for dot_y in range(low, high + 1):
                canvas.set(x, dot_y, layer)
            previous = y
    return canvas, top_n


def _finite(series: Sequence[float | None]) -> list[float | None]:
    return [v if v is not None and math.isfinite(v) else None for v in series]


class ForcePlot(Static):
    """Force of one vehicle against its target since its current job began; hidden until a
    telemetry sample of the vehicle carries a force (kinds without force never show it)."""

    def __init__(self, model: ConsoleModel, vehicle_id: str, **kwargs: object) -> None:
        super().__init__(**kwargs)  # type: ignore[arg-type]
        self.model = model
        self.vehicle_id = vehicle_id
        self._drawn: tuple[int, int, int, int] | None = None
        self.canvas: BrailleCanvas | None = None
        """The plot last drawn (None before, or while the track has no force)."""
        self.border_subtitle = LEGEND
        self.display = False

    def sync(self) -> None:
        """Draw again if the track changed since the last call (or the size did)."""
        track = self.model.track(self.vehicle_id)
        if track is None:
            return
        points = track.points
        has_force = bool(points) and points[-1].force_n is not None
        if not (self.display or has_force):
            return
        self.display = True
        cols, rows = self.content_size.width, self.content_size.height
        key = (track.generation, track.count, cols, rows)
        if cols < 1 or rows < 1 or key == self._drawn:
            return
        self._drawn = key
        if not has_force:
            self.canvas = None
            self.border_title = Text("force")
            self.update(Text(NO_FORCE, style="dim"))
            return
        measured, target = force_series(points, 2 * cols)
        canvas, top_n = plot_force(measured, target, cols, rows)
        self.canvas = canvas
        self.border_title = Text(f"force 0..{top_n:.1f} N over the job")
        self.update(canvas.to_text(PLOT_STYLES))
