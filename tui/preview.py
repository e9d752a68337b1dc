"""A small preview of a submission: strokes JSON drawn in braille, or the typed text.

The console may not import the planner, so it reads the strokes document itself, leniently: only
``strokes`` (lists of ``[x, y]`` or ``[x, y, t]`` points) and ``y_axis`` (``up`` or ``down``,
default ``up``) matter here; anything unreadable yields no preview rather than an error.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

from rich.text import Text

from tui.braille import BrailleCanvas, apply_transform, fit_transform
from tui.safe_text import clean

Polyline = list[tuple[float, float]]


def stroke_polylines(document: Mapping[str, Any] | None) -> tuple[list[Polyline], bool]:
    """The finite polylines of a strokes document and whether its y axis points up."""
    if not isinstance(document, Mapping):
        return [], True
    y_up = str(document.get("y_axis", "up")).lower() != "down"
    strokes = document.get("strokes")
    if not isinstance(strokes, list):
        return [], y_up
    result: list[Polyline] = []
    for stroke in strokes:
        if not isinstance(stroke, list):
            continue
        points: Polyline = []
        for point in stroke:
            xy = _point(point)
            if xy is not None:
                points.append(xy)
        if points:
            result.append(points)
    return result, y_up


def _point(point: object) -> tuple[float, float] | None:
    if not isinstance(point, list | tuple) or len(point) < 2:
        return None
    try:
        x, y = float(point[0]), float(point[1])
    except (TypeError, ValueError):
        return None
    return (x, y) if math.isfinite(x) and math.isfinite(y) else None


def render_strokes(
    document: Mapping[str, Any] | None, cols: int, rows: int, style: str = "bold"
) -> Text | None:
    """Braille drawing of a strokes document fitted into ``cols`` x ``rows`` cells, or None."""
    polylines, y_up = stroke_polylines(document)
    if not polylines:
        return None
    xs = [x for line in polylines for x, _ in line]
    ys = [y for line in polylines for _, y in line]
    canvas = BrailleCanvas(cols, rows)
    transform = fit_transform(
        (min(xs), min(ys), max(xs), max(ys)), canvas.width_dots, canvas.height_dots, y_up=y_up
    )
    for line in polylines:
        canvas.polyline([apply_transform(transform, x, y) for x, y in line])
    return canvas.to_text([style])


def render_preview(
    text: str | None, strokes: Mapping[str, Any] | None, label: str, cols: int, rows: int
) -> Text:
    """What to show for a submission: its strokes drawn, else its text, else its label."""
    drawn = render_strokes(strokes, cols, rows) if strokes else None
    if drawn is not None:
        return drawn
    shown = clean(text if text else label)
    return Text(shown, style="bold", justify="center", no_wrap=False)
