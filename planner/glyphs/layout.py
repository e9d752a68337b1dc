"""Place a glyph on a writing area: uniform scale to fit, centred, in metres."""

from __future__ import annotations

import math

import numpy as np

from planner.errors import PlannerError
from planner.glyphs.glyph import Glyph


def fit_to_area(glyph: Glyph, *, width_m: float, height_m: float, margin_m: float = 0.0) -> Glyph:
    """Scale ``glyph`` (aspect ratio kept) to the largest size inside the area less the margins.

    The result is in metres, y up, its ink bounding box centred on (0, 0), the centre of the
    writing area. The area is ``width_m`` x ``height_m``; ``margin_m`` is kept free on every
    side. Times (if any) are unchanged. A glyph that is a straight horizontal or vertical line
    is scaled by its one non-zero extent.
    """
    width = _number("width_m", width_m, positive=True)
    height = _number("height_m", height_m, positive=True)
    margin = _number("margin_m", margin_m, positive=False)
    inner = np.array([width - 2.0 * margin, height - 2.0 * margin])
    if inner.min() <= 0.0:
        raise PlannerError(
            f"margins of {margin} m leave no room in a {width} m x {height} m area",
            field="margin_m",
        )
    x_min, y_min, x_max, y_max = glyph.bounds()
    extent = np.array([x_max - x_min, y_max - y_min])
    usable = extent > 0.0
    if not usable.any():
        raise PlannerError("the glyph has no extent (all points equal)", field="strokes")
    with np.errstate(over="ignore", divide="ignore"):
        scale = float(np.min(inner[usable] / extent[usable]))
    if not math.isfinite(scale):
        raise PlannerError("the glyph is too small to scale", field="strokes")
    centre = np.array([(x_min + x_max) / 2.0, (y_min + y_max) / 2.0])
    return Glyph(
        strokes=tuple((s - centre) * scale for s in glyph.strokes),
        times_s=glyph.times_s,
        units="m",
        label=glyph.label,
        source=glyph.source,
    )


def _number(field: str, value: float, *, positive: bool) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PlannerError(f"must be a number, got {type(value).__name__}", field=field)
    number = float(value)
    if not math.isfinite(number) or number < 0.0 or (positive and number == 0.0):
        bound = "> 0" if positive else ">= 0"
        raise PlannerError(f"must be finite and {bound}, got {number}", field=field)
    return number
