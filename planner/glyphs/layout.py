"""Place a glyph on a writing area: uniform scale to fit, centred, in metres."""

from __future__ import annotations

import math

import numpy as np

from planner.errors import PlannerError
from planner.glyphs.glyph import Glyph


def fit_to_area(glyph: Glyph, *, width_m: float, height_m: float, margin_m: float = 0.0) -> Glyph:
    """Scale ``glyph`` (aspect ratio kept) to the largest size inside the area less the margins.

    A glyph with a drawing area (``frame``, from a strokes document's canvas) is laid out
    canvas-relative: the drawing area, not the ink, is fitted and centred, so a small character
    drawn in a corner stays small and in that corner; a drawing whose ink spans less than
    :data:`MIN_INK_FRACTION` of its canvas (a tap) is refused.

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
    if glyph.frame is not None:  # canvas-relative: the drawing area maps onto the writing area
        fraction = ink_fraction(glyph)
        if fraction is not None and fraction < MIN_INK_FRACTION:
            raise PlannerError(
                f"the drawing spans {100 * fraction:.1f}% of its canvas, less than "
                f"{100 * MIN_INK_FRACTION:g}% (a tap, not a drawing)",
                field="strokes",
            )
        x_min, y_min, x_max, y_max = _union(glyph.frame, (x_min, y_min, x_max, y_max))
        extent = np.array([x_max - x_min, y_max - y_min])
        usable = extent > 0.0
    with np.errstate(over="ignore", divide="ignore"):
        scale = float(np.min(inner[usable] / extent[usable]))
    if not math.isfinite(scale):
        raise PlannerError("the glyph is too small to scale", field="strokes")
    centre = np.array([(x_min + x_max) / 2.0, (y_min + y_max) / 2.0])
    frame = None
    if glyph.frame is not None:  # the laid-out drawing area (fitting again changes nothing)
        half_w, half_h = scale * (x_max - x_min) / 2.0, scale * (y_max - y_min) / 2.0
        frame = (-half_w, -half_h, half_w, half_h)
    return Glyph(
        strokes=tuple((s - centre) * scale for s in glyph.strokes),
        times_s=glyph.times_s,
        units="m",
        label=glyph.label,
        source=glyph.source,
        frame=frame,
        widths_m=glyph.widths_m,  # pen widths are physical: laying out does not scale them
    )


MIN_INK_FRACTION = 0.05
"""Smallest ink extent of a drawing with a canvas, as a fraction of the canvas's longer side."""


def ink_fraction(glyph: Glyph) -> float | None:
    """Longer side of the ink's bounding box over the longer side of the glyph's drawing area
    (None without a drawing area)."""
    if glyph.frame is None:
        return None
    fx0, fy0, fx1, fy1 = glyph.frame
    x_min, y_min, x_max, y_max = glyph.bounds()
    side = max(fx1 - fx0, fy1 - fy0)
    return max(x_max - x_min, y_max - y_min) / side if side > 0.0 else None


def _union(
    a: tuple[float, float, float, float], b: tuple[float, float, float, float]
) -> tuple[float, float, float, float]:
    """Bounding box of two boxes (ink drawn past the canvas edge widens the frame)."""
    return (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3]))


def _number(field: str, value: float, *, positive: bool) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PlannerError(f"must be a number, got {type(value).__name__}", field=field)
    number = float(value)
    if not math.isfinite(number) or number < 0.0 or (positive and number == 0.0):
        bound = "> 0" if positive else ">= 0"
        raise PlannerError(f"must be finite and {bound}, got {number}", field=field)
    return number
