"""The one glyph type every source produces: ordered pen-down polylines, y axis up."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planner.errors import PlannerError

FloatArray = NDArray[np.float64]

GLYPH_UNITS = ("m", "px", "em")
"""Units a glyph may carry: metres, pixels of a drawing canvas, or font em (1 em = CJK cell)."""


@dataclass(frozen=True, eq=False)
class Glyph:
    """Something to write: strokes in writing order, each a pen-down polyline.

    Arrays are read-only copies; compare glyphs with :func:`glyphs_equal`, not ``==``.
    """

    strokes: tuple[FloatArray, ...]
    """Per stroke an (n_i, 2) array of points (x, y), n_i >= 2, y axis UP, in ``units``."""
    times_s: tuple[FloatArray | None, ...]
    """Per stroke the (n_i,) point times in [s] when the source had them, else None."""
    units: str
    """"m", "px" or "em" (font units: 1 em is the height of a CJK character cell)."""
    label: str
    """What this is, for people: the typed text or the handwriting file's label or name."""
    source: str
    """Where it came from: "strokes-json", "hershey:<font>", "hanzi-writer-data" or a mix."""
    frame: tuple[float, float, float, float] | None = None
    """The drawing area the strokes were drawn in, ``(x_min, y_min, x_max, y_max)`` in ``units``,
    y up (a strokes document's ``canvas``); None: the ink itself is the whole picture."""
    widths_m: tuple[FloatArray | None, ...] = ()
    """Per stroke the (n_i,) wanted line widths in [m] (physical, not scaled by layout) when
    the source had them, else None; ``()``: no stroke has widths."""

    def __post_init__(self) -> None:
        if self.units not in GLYPH_UNITS:
            raise PlannerError(
                f"unknown units {self.units!r}, expected one of {GLYPH_UNITS}", field="units"
            )
        if not self.strokes:
            raise PlannerError("a glyph needs at least one stroke", field="strokes")
        if len(self.times_s) != len(self.strokes):
            raise PlannerError(
                f"{len(self.times_s)} time arrays for {len(self.strokes)} strokes", field="times_s"
            )
        strokes = tuple(_frozen_points(s, i) for i, s in enumerate(self.strokes))
        times = tuple(
            None if t is None else _frozen_times(t, strokes[i].shape[0], i)
            for i, t in enumerate(self.times_s)
        )
        object.__setattr__(self, "strokes", strokes)
        object.__setattr__(self, "times_s", times)
        if self.widths_m:
            if len(self.widths_m) != len(self.strokes):
                raise PlannerError(
                    f"{len(self.widths_m)} width arrays for {len(self.strokes)} strokes",
                    field="widths_m",
                )
            widths = tuple(
                None if w is None else _frozen_widths(w, strokes[i].shape[0], i)
                for i, w in enumerate(self.widths_m)
            )
            object.__setattr__(self, "widths_m", widths)

    @property
    def point_count(self) -> int:
        """Total number of points over all strokes."""
        return sum(s.shape[0] for s in self.strokes)

    def bounds(self) -> tuple[float, float, float, float]:
        """Ink bounding box ``(x_min, y_min, x_max, y_max)`` in ``units``."""
        allpts = np.concatenate(self.strokes, axis=0)
        lo = allpts.min(axis=0)
        hi = allpts.max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])


def _frozen_points(points: FloatArray, stroke_index: int) -> FloatArray:
    arr = np.array(points, dtype=np.float64)
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise PlannerError(
            f"points must have shape (n, 2), got {arr.shape}", stroke_index=stroke_index
        )
    if arr.shape[0] < 2:
        raise PlannerError("a stroke needs at least 2 points", stroke_index=stroke_index)
    bad = np.flatnonzero(~np.isfinite(arr).all(axis=1))
    if bad.size:
        raise PlannerError(
            "coordinate is not finite", stroke_index=stroke_index, point_index=int(bad[0])
        )
    arr.flags.writeable = False
    return arr


def _frozen_times(times: FloatArray, n_points: int, stroke_index: int) -> FloatArray:
    arr = np.array(times, dtype=np.float64)
    if arr.shape != (n_points,):
        raise PlannerError(
            f"times must have shape ({n_points},), got {arr.shape}",
            stroke_index=stroke_index,
            field="times_s",
        )
    bad = np.flatnonzero(~np.isfinite(arr) | np.r_[False, np.diff(arr) < 0])
    if bad.size:
        raise PlannerError(
            "times must be finite and non-decreasing",
            stroke_index=stroke_index,
            point_index=int(bad[0]),
            field="times_s",
        )
    arr.flags.writeable = False
    return arr


def _frozen_widths(widths: FloatArray, n_points: int, stroke_index: int) -> FloatArray:
    arr = np.array(widths, dtype=np.float64)
    if arr.shape != (n_points,):
        raise PlannerError(
            f"widths must have shape ({n_points},), got {arr.shape}",
            stroke_index=stroke_index,
            field="widths_m",
        )
    bad = np.flatnonzero(~np.isfinite(arr) | (arr <= 0.0))
    if bad.size:
        raise PlannerError(
            "width must be finite and positive",
            stroke_index=stroke_index,
            point_index=int(bad[0]),
            field="widths_m",
        )
    arr.flags.writeable = False
    return arr


def kept_points(points: FloatArray) -> NDArray[np.bool_]:
    """(n,) True for each point kept by :func:`merge_repeated_points`."""
    return np.asarray(np.r_[True, np.any(np.diff(points, axis=0) != 0.0, axis=1)])


def merge_repeated_points(
    points: FloatArray, times: FloatArray | None
) -> tuple[FloatArray, FloatArray | None]:
    """Drop points equal to their predecessor (x and y both); the first of a run keeps its time."""
    keep = kept_points(points)
    return points[keep], (None if times is None else times[keep])


def glyphs_equal(a: Glyph, b: Glyph) -> bool:
    """True when both glyphs have the same metadata and exactly the same arrays."""
    if (a.units, a.label, a.source, len(a.strokes)) != (b.units, b.label, b.source, len(b.strokes)):
        return False
    for sa, sb, ta, tb in zip(a.strokes, b.strokes, a.times_s, b.times_s, strict=True):
        if not np.array_equal(sa, sb):
            return False
        if ta is None or tb is None:
            if ta is not tb:
                return False
        elif not np.array_equal(ta, tb):
            return False
    return True


def concat_glyphs(parts: Sequence[Glyph], *, label: str, source: str) -> Glyph:
    """Join glyphs of the same units into one, strokes in the given order."""
    units = {g.units for g in parts}
    if len(units) != 1:
        raise PlannerError(f"cannot join glyphs in different units {sorted(units)}", field="units")
    strokes = tuple(s for g in parts for s in g.strokes)
    times = tuple(t for g in parts for t in g.times_s)
    widths: tuple[FloatArray | None, ...] = ()
    if any(g.widths_m for g in parts):
        widths = tuple(w for g in parts for w in (g.widths_m or (None,) * len(g.strokes)))
    return Glyph(
        strokes=strokes,
        times_s=times,
        units=units.pop(),
        label=label,
        source=source,
        widths_m=widths,
    )
