"""Handwriting in: parse and validate the strokes JSON format (docs/formats.md).

Every error is a :class:`PlannerError` that names the field, stroke and point (indices as they are
in the document, counted from 0) so a person can find the mistake in the file.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping
from typing import Any, TypeGuard

import numpy as np

from planner.errors import PlannerError
from planner.glyphs.glyph import FloatArray, Glyph, kept_points, merge_repeated_points

MAX_STROKES = 200
"""Most strokes one document may hold."""
MAX_POINTS = 20_000
"""Most points one document may hold, all strokes together (before merging repeats)."""
MAX_DOCUMENT_CHARS = 2_000_000
"""Longest JSON text accepted; checked before parsing so that huge inputs fail fast."""
UNITS = ("px", "m")
"""Units of a strokes document: canvas pixels or metres."""
Y_AXES = ("down", "up")
"""Direction of +y in a strokes document: "down" as on screens, or "up"."""
MAX_WIDTH_M = 1.0
"""Largest per-point line width ``w`` in [m] a document may ask for (the vehicle kind checks
its own pen's range)."""
MAX_COORDINATE = 1e6
"""Largest |x|, |y| of a point and largest canvas side, in the document's units (px or m).
Beyond it a drawing could not be scaled onto a board without overflowing floats."""

_MAX_TEXT_FIELD_CHARS = 200


def parse_strokes_json(
    doc: str | bytes | Mapping[str, Any], *, source_name: str = "<strokes>"
) -> Glyph:
    """Read a strokes document (JSON text or an already parsed mapping) into a y-up glyph.

    Consecutive points with equal x and y are merged (the first keeps its time): touch screens
    repeat samples. A stroke left with fewer than 2 distinct points is an error. With
    ``y_axis == "down"`` the y coordinate is negated, x is unchanged.
    """
    data = _load(doc, source_name)
    units = _enum_field(data, "units", UNITS, source_name)
    y_axis = _enum_field(data, "y_axis", Y_AXES, source_name)
    label = _optional_text(data, "label", source_name)
    _optional_text(data, "device", source_name)
    frame: tuple[float, float, float, float] | None = None
    if "canvas" in data:
        _check_canvas(data["canvas"], source_name)
        width, height = _as_float(data["canvas"]["width"]), _as_float(data["canvas"]["height"])
        frame = (0.0, -height, width, 0.0) if y_axis == "down" else (0.0, 0.0, width, height)
    raw_strokes = _stroke_lists(data, source_name)
    timed = _has_time(raw_strokes[0][0])
    wide = _has_width(raw_strokes[0][0])
    strokes: list[FloatArray] = []
    times: list[FloatArray | None] = []
    widths: list[FloatArray | None] = []
    previous_end_s: float | None = None
    for i, raw in enumerate(raw_strokes):
        points, t, w = _parse_stroke(raw, i, (timed, wide), source_name)
        if t is not None:
            if previous_end_s is not None and t[0] < previous_end_s:
                raise PlannerError(
                    f"{source_name}: time {t[0]} s is before the end of the previous stroke "
                    f"({previous_end_s} s)",
                    field="strokes",
                    stroke_index=i,
                    point_index=0,
                )
            previous_end_s = float(t[-1])
        if y_axis == "down":
            points[:, 1] = -points[:, 1]
        if w is not None:
            w = w[kept_points(points)]
        points, t = merge_repeated_points(points, t)
        if points.shape[0] < 2:
            raise PlannerError(
                f"{source_name}: zero-length stroke (all {len(raw)} points are equal)",
                field="strokes",
                stroke_index=i,
            )
        strokes.append(points)
        times.append(t)
        widths.append(w)
    return Glyph(
        strokes=tuple(strokes),
        times_s=tuple(times),
        units=units,
        label=label if label is not None else source_name,
        source="strokes-json",
        frame=frame,
        widths_m=tuple(widths) if wide else (),
    )


def _load(doc: str | bytes | Mapping[str, Any], source_name: str) -> Mapping[str, Any]:
    if isinstance(doc, Mapping):
        return doc
    if isinstance(doc, bytes | bytearray):
        if len(doc) > MAX_DOCUMENT_CHARS * 4:
            raise PlannerError(f"{source_name}: document too large ({len(doc)} bytes)")
        try:
            doc = bytes(doc).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise PlannerError(f"{source_name}: not UTF-8 text ({exc.reason})") from None
    if not isinstance(doc, str):
        raise PlannerError(f"{source_name}: expected JSON text or a mapping, got {type(doc)}")
    if len(doc) > MAX_DOCUMENT_CHARS:
        raise PlannerError(
            f"{source_name}: document too large ({len(doc)} characters, "
            f"limit {MAX_DOCUMENT_CHARS}; at most {MAX_POINTS} points are allowed)"
        )
    try:
        data = json.loads(doc)
    except json.JSONDecodeError as exc:
        raise PlannerError(
            f"{source_name}: invalid JSON at line {exc.lineno} column {exc.colno}: {exc.msg}"
        ) from None
    except RecursionError:
        raise PlannerError(f"{source_name}: JSON nested too deeply") from None
    if not isinstance(data, dict):
        raise PlannerError(f"{source_name}: the top level must be a JSON object, got {_kind(data)}")
    return data


def _kind(value: Any) -> str:
    names = {dict: "object", list: "array", str: "string", bool: "boolean", type(None): "null"}
    for typ, name in names.items():
        if isinstance(value, typ):
            return name
    return "number" if isinstance(value, int | float) else type(value).__name__


def _enum_field(
    data: Mapping[str, Any], name: str, allowed: tuple[str, ...], source_name: str
) -> str:
    if name not in data:
        raise PlannerError(f"{source_name}: missing required field, one of {allowed}", field=name)
    value = data[name]
    if not isinstance(value, str) or value not in allowed:
        raise PlannerError(f"{source_name}: {value!r} is not one of {allowed}", field=name)
    return value


def _optional_text(data: Mapping[str, Any], name: str, source_name: str) -> str | None:
    if name not in data:
        return None
    value = data[name]
    if not isinstance(value, str) or len(value) > _MAX_TEXT_FIELD_CHARS:
        raise PlannerError(
            f"{source_name}: must be a string of at most {_MAX_TEXT_FIELD_CHARS} characters",
            field=name,
        )
    return value


def _check_canvas(canvas: Any, source_name: str) -> None:
    if not isinstance(canvas, dict):
        raise PlannerError(f"{source_name}: must be an object, got {_kind(canvas)}", field="canvas")
    for key in ("width", "height"):
        value = canvas.get(key)
        if not _is_number(value) or not 0 < _as_float(value) <= MAX_COORDINATE:
            raise PlannerError(
                f"{source_name}: must be a positive number at most {MAX_COORDINATE:g}, "
                f"got {_short(value)}",
                field=f"canvas.{key}",
            )


def _stroke_lists(data: Mapping[str, Any], source_name: str) -> list[list[Any]]:
    if "strokes" not in data:
        raise PlannerError(f"{source_name}: missing required field", field="strokes")
    strokes = data["strokes"]
    if not isinstance(strokes, list):
        raise PlannerError(
            f"{source_name}: must be an array of strokes, got {_kind(strokes)}", field="strokes"
        )
    if not strokes:
        raise PlannerError(f"{source_name}: no strokes", field="strokes")
    if len(strokes) > MAX_STROKES:
        raise PlannerError(
            f"{source_name}: too many strokes ({len(strokes)}, limit {MAX_STROKES})",
            field="strokes",
        )
    total = 0
    for i, stroke in enumerate(strokes):
        if not isinstance(stroke, list):
            raise PlannerError(
                f"{source_name}: a stroke must be an array of points, got {_kind(stroke)}",
                field="strokes",
                stroke_index=i,
            )
        if len(stroke) < 2:
            raise PlannerError(
                f"{source_name}: a stroke needs at least 2 points, got {len(stroke)}",
                field="strokes",
                stroke_index=i,
            )
        total += len(stroke)
        if total > MAX_POINTS:
            raise PlannerError(
                f"{source_name}: too many points (more than {MAX_POINTS} in strokes 0..{i})",
                field="strokes",
                stroke_index=i,
            )
    return strokes


def _short(value: Any) -> str:
    """``repr`` of a value cut to 40 characters (a 4,000-digit integer stays readable)."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:37]}..."


def _has_time(point: Any) -> bool:
    if isinstance(point, Mapping):
        return "t" in point
    return isinstance(point, list) and len(point) >= 3


def _has_width(point: Any) -> bool:
    return isinstance(point, Mapping) and "w" in point


def _is_number(value: Any) -> TypeGuard[int | float]:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _as_float(value: int | float) -> float:
    """The value as a float; integers too large for a float become inf."""
    try:
        return float(value)
    except OverflowError:
        return math.inf


def _parse_stroke(
    raw: list[Any], stroke_index: int, first: tuple[bool, bool], source_name: str
) -> tuple[FloatArray, FloatArray | None, FloatArray | None]:
    """Points, times and widths of one stroke; ``first`` says whether the document's first
    point had a time and a width (every point must then be the same)."""
    timed, wide = first
    n = len(raw)
    points = np.empty((n, 2), dtype=np.float64)
    times = np.empty(n, dtype=np.float64) if timed else None
    widths = np.empty(n, dtype=np.float64) if wide else None
    for j, point in enumerate(raw):
        values, width = _point_values(point, stroke_index, j, source_name)
        for has, wanted, what in (
            (len(values) >= 3, timed, "time t"),
            (width is not None, wide, "width w"),
        ):
            if has != wanted:
                first_has = "has a" if wanted else "has no"
                raise PlannerError(
                    f"{source_name}: the first point of the document {first_has} {what}; "
                    "every point must then be the same",
                    field="strokes",
                    stroke_index=stroke_index,
                    point_index=j,
                )
        points[j] = values[0], values[1]
        if widths is not None and width is not None:
            widths[j] = width
        if times is not None:
            times[j] = values[2]
            if j > 0 and times[j] < times[j - 1]:
                raise PlannerError(
                    f"{source_name}: time decreases ({times[j - 1]} s then {times[j]} s)",
                    field="strokes",
                    stroke_index=stroke_index,
                    point_index=j,
                )
    return points, times, widths


_COORD_NAMES = ("x", "y", "t", "pressure")


def _point_values(
    point: Any, stroke_index: int, point_index: int, source_name: str
) -> tuple[list[float], float | None]:
    """The point's numbers ``[x, y, (t, (pressure))]`` and its width ``w`` in [m] or None."""

    def fail(message: str) -> PlannerError:
        return PlannerError(
            f"{source_name}: {message}",
            field="strokes",
            stroke_index=stroke_index,
            point_index=point_index,
        )

    width: float | None = None
    if isinstance(point, Mapping):
        point, width = _object_point(point, fail)
    if not isinstance(point, list) or not 2 <= len(point) <= 4:
        got = f"{len(point)} values" if isinstance(point, list) else _kind(point)
        raise fail(
            "a point must be [x, y], [x, y, t], [x, y, t, pressure] or an object "
            f"{{x, y, t?, pressure?, w?}}, got {got}"
        )
    values: list[float] = []
    for name, value in zip(_COORD_NAMES, point, strict=False):
        if not _is_number(value):
            raise fail(f"{name} must be a number, got {_kind(value)}")
        number = _as_float(value)
        if not math.isfinite(number):
            raise fail(f"{name} is not finite ({_short(value)})")
        if name in ("x", "y") and abs(number) > MAX_COORDINATE:
            raise fail(f"|{name}| must be at most {MAX_COORDINATE:g}, got {number!r}")
        if name == "pressure" and number < 0.0:
            raise fail(f"pressure must be >= 0, got {number}")
        values.append(number)
    return values, width


def _object_point(
    point: Mapping[str, Any], fail: Callable[[str], PlannerError]
) -> tuple[list[Any], float | None]:
    """``{x, y, t?, pressure?, w?}`` -> the array form and the width in [m] (checked)."""
    unknown = sorted(set(point) - {"x", "y", "t", "pressure", "w"})
    if unknown:
        raise fail(f"unknown point key {_short(unknown[0])}; expected x, y, t, pressure, w")
    for key in ("x", "y"):
        if key not in point:
            raise fail(f"a point object needs {key}")
    if "pressure" in point and "t" not in point:
        raise fail("pressure needs t")
    values = [point[k] for k in ("x", "y", "t", "pressure") if k in point]
    if "w" not in point:
        return values, None
    w = point["w"]
    if not _is_number(w) or not math.isfinite(_as_float(w)):
        raise fail(f"w must be a finite number in metres, got {_short(w)}")
    if not 0.0 < _as_float(w) <= MAX_WIDTH_M:
        raise fail(f"w must be in (0, {MAX_WIDTH_M:g}] m, got {_as_float(w)!r}")
    return values, _as_float(w)
