"""Handwriting in: parsing and validating strokes JSON documents."""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from planner.errors import PlannerError
from planner.glyphs import MAX_POINTS, MAX_STROKES, parse_strokes_json

DATA = Path(__file__).parent / "data"


def doc(strokes: Any, **extra: Any) -> dict[str, Any]:
    base: dict[str, Any] = {"units": "px", "y_axis": "down", "strokes": strokes}
    base.update(extra)
    return base


def test_px_y_down_is_flipped_to_y_up() -> None:
    g = parse_strokes_json(doc([[[10, 20, 0.0], [30, 50, 0.5]]]), source_name="a.json")
    assert g.units == "px"
    assert g.source == "strokes-json"
    assert g.label == "a.json"
    np.testing.assert_array_equal(g.strokes[0], [[10.0, -20.0], [30.0, -50.0]])
    assert g.times_s[0] is not None
    np.testing.assert_array_equal(g.times_s[0], [0.0, 0.5])


def test_m_y_up_is_kept() -> None:
    g = parse_strokes_json(json.dumps(doc([[[0.1, 0.2], [0.3, 0.4]]], units="m", y_axis="up")))
    assert g.units == "m"
    np.testing.assert_array_equal(g.strokes[0], [[0.1, 0.2], [0.3, 0.4]])
    assert g.times_s == (None,)


def test_handwritten_s_sample() -> None:
    text = (DATA / "handwritten_S_px.json").read_text(encoding="utf-8")
    raw = json.loads(text)
    g = parse_strokes_json(text, source_name="handwritten_S_px.json")
    assert g.label == "S"
    assert len(g.strokes) == 1
    # the sample repeats two samples exactly, as touch screens do: they are merged
    assert g.strokes[0].shape[0] == len(raw["strokes"][0]) - 2
    # screen y down -> y up: the stroke starts near the top (largest y) of the ink
    first_y = g.strokes[0][0, 1]
    assert first_y > np.median(g.strokes[0][:, 1])
    assert first_y == -raw["strokes"][0][0][1]


def test_gong_sample_has_three_timed_strokes_in_order() -> None:
    g = parse_strokes_json((DATA / "handwritten_gong_px.json").read_bytes())
    assert g.label == "工"
    assert len(g.strokes) == 3
    horizontal_top, vertical, horizontal_bottom = g.strokes
    # stroke order of 工: top bar (left to right), down stroke, bottom bar below the top one
    assert horizontal_top[-1, 0] > horizontal_top[0, 0]
    assert vertical[-1, 1] < vertical[0, 1]
    assert horizontal_bottom[:, 1].mean() < horizontal_top[:, 1].mean()
    ends = [float(t[-1]) for t in g.times_s if t is not None]
    starts = [float(t[0]) for t in g.times_s if t is not None]
    assert all(s >= e for s, e in zip(starts[1:], ends[:-1], strict=True))


def test_metre_sample_without_times() -> None:
    g = parse_strokes_json((DATA / "l_tick_m_up.json").read_text(encoding="utf-8"))
    assert g.units == "m"
    assert all(t is None for t in g.times_s)
    assert g.bounds() == (0.0, 0.0, 0.75, 0.6)


def test_repeated_points_merge_and_keep_first_time() -> None:
    g = parse_strokes_json(doc([[[0, 0, 0.0], [0, 0, 0.1], [1, 0, 0.2], [1, 0, 0.3], [2, 0, 0.4]]]))
    np.testing.assert_array_equal(g.strokes[0][:, 0], [0.0, 1.0, 2.0])
    assert g.times_s[0] is not None
    np.testing.assert_array_equal(g.times_s[0], [0.0, 0.2, 0.4])


def test_non_consecutive_repeats_are_kept() -> None:
    g = parse_strokes_json(doc([[[0, 0], [1, 1], [0, 0]]]))
    assert g.strokes[0].shape == (3, 2)


def test_pressure_is_accepted() -> None:
    g = parse_strokes_json(doc([[[0, 0, 0.0, 0.5], [1, 1, 0.1, 0.7]]]))
    assert g.strokes[0].shape == (2, 2)


def test_extra_fields_and_canvas_are_allowed() -> None:
    g = parse_strokes_json(doc([[[0, 0], [1, 1]]], canvas={"width": 10, "height": 5}, app="x"))
    assert len(g.strokes) == 1


def test_glyph_arrays_are_read_only() -> None:
    g = parse_strokes_json(doc([[[0, 0], [1, 1]]]))
    with pytest.raises(ValueError, match="read-only"):
        g.strokes[0][0, 0] = 5.0


def test_bad_json_reports_line_and_column() -> None:
    with pytest.raises(PlannerError, match=r"S\.json: invalid JSON at line 3 column 5"):
        parse_strokes_json('{\n  "units": "px",\n    ]', source_name="S.json")


def error_of(document: Any) -> PlannerError:
    with pytest.raises(PlannerError) as info:
        parse_strokes_json(document)
    return info.value


@pytest.mark.parametrize(
    ("document", "field", "stroke", "point", "words"),
    [
        ("[1, 2]", None, None, None, "top level must be a JSON object, got array"),
        ({"units": "px", "y_axis": "down"}, "strokes", None, None, "missing"),
        ({"strokes": [[[0, 0], [1, 1]]], "y_axis": "up"}, "units", None, None, "missing"),
        (doc([[[0, 0], [1, 1]]], units="cm"), "units", None, None, "'cm' is not one of"),
        (doc([[[0, 0], [1, 1]]], y_axis=1), "y_axis", None, None, "1 is not one of"),
        (doc([[[0, 0], [1, 1]]], label=3), "label", None, None, "string"),
        (
            doc([[[0, 0], [1, 1]]], canvas={"width": 0, "height": 1}),
            "canvas.width",
            None,
            None,
            "positive",
        ),
        (doc([[[0, 0], [1, 1]]], canvas=[1, 2]), "canvas", None, None, "object"),
        (doc({"a": 1}), "strokes", None, None, "array of strokes"),
        (doc([]), "strokes", None, None, "no strokes"),
        (doc([[[0, 0], [1, 1]], "ab"]), "strokes", 1, None, "array of points"),
        (doc([[[0, 0], [1, 1]], [[2, 2]]]), "strokes", 1, None, "at least 2 points"),
        (doc([[[0, 0], [1, 1], [1, "2"]]]), "strokes", 0, 2, "y must be a number, got string"),
        (doc([[[0, 0], [True, 1]]]), "strokes", 0, 1, "x must be a number, got boolean"),
        (doc([[[0, 0], [1]]]), "strokes", 0, 1, "got 1 values"),
        (doc([[[0, 0], [1, 1, 2, 3, 4]]]), "strokes", 0, 1, "got 5 values"),
        (doc([[[0, 0], {"x": 1}]]), "strokes", 0, 1, "a point object needs y"),
        (doc([[[0, 0], [1, math.nan]]]), "strokes", 0, 1, "y is not finite"),
        (doc([[[0, 0], [1, 1]], [[0, 0], [math.inf, 1]]]), "strokes", 1, 1, "x is not finite"),
        (doc([[[0, 0], [1, 10**400]]]), "strokes", 0, 1, "y is not finite"),
        (doc([[[0, 0, 0.0], [1, 1, math.nan]]]), "strokes", 0, 1, "t is not finite"),
        (
            doc([[[0, 0], [1, 1]], [[0, 0], [1, 1], [2, 2], [1e308, 1]]]),
            "strokes",
            1,
            3,
            "|x| must be at most 1e+06, got 1e+308",
        ),
        (doc([[[0, 0], [1, -1_000_001]]]), "strokes", 0, 1, "|y| must be at most 1e+06"),
        (
            doc([[[0, 0], [1, 1]]], canvas={"width": 1, "height": 1e7}),
            "canvas.height",
            None,
            None,
            "at most 1e+06",
        ),
        (doc([[[0, 0, 0, 0.5], [1, 1, 1, -0.1]]]), "strokes", 0, 1, "pressure must be >= 0"),
        (doc([[[0, 0], [1, 1]], [[5, 5], [5, 5], [5, 5]]]), "strokes", 1, None, "zero-length"),
        (doc([[[0, 0, 0.0], [1, 1, 0.2], [2, 2, 0.1]]]), "strokes", 0, 2, "time decreases"),
        (
            doc([[[0, 0, 0.0], [1, 1, 2.0]], [[3, 3, 1.0], [4, 4, 3.0]]]),
            "strokes",
            1,
            0,
            "before the end of the previous stroke",
        ),
        (doc([[[0, 0, 0.0], [1, 1]]]), "strokes", 0, 1, "has a time t"),
        (doc([[[0, 0], [1, 1]], [[2, 2, 0.5], [3, 3, 0.6]]]), "strokes", 1, 0, "has no time t"),
        (doc([[[0, 0], [1, 1]]] * (MAX_STROKES + 1)), "strokes", None, None, "too many strokes"),
    ],
)
def test_errors_name_field_stroke_and_point(
    document: Any, field: str | None, stroke: int | None, point: int | None, words: str
) -> None:
    err = error_of(document)
    assert (err.field, err.stroke_index, err.point_index) == (field, stroke, point)
    assert words in str(err)
    if stroke is not None:
        assert f"stroke {stroke}" in str(err)
    if point is not None:
        assert f"point {point}" in str(err)


def test_nan_in_json_text_names_the_point() -> None:
    err = error_of('{"units": "px", "y_axis": "up", "strokes": [[[0, 0], [NaN, 1]]]}')
    assert (err.stroke_index, err.point_index) == (0, 1)


def test_too_many_points_is_rejected_before_reading_points() -> None:
    # a million points in one stroke: rejected by counting, the points themselves are not parsed
    # (they are not even valid points, which would be a different error)
    huge = doc([[[0, 0], [1, 1]], ["not a point"] * 1_000_000])
    err = error_of(huge)
    assert "too many points" in str(err)
    assert err.stroke_index == 1


def test_points_limit_is_inclusive() -> None:
    n = MAX_POINTS // 2
    ok = doc([[[float(i), 0.0] for i in range(n)], [[float(i), 1.0] for i in range(n)]])
    assert parse_strokes_json(ok).point_count == MAX_POINTS
    ok["strokes"][1].append([0.0, 5.0])
    assert "too many points" in str(error_of(ok))


def test_huge_json_text_is_rejected_before_parsing() -> None:
    text = json.dumps(doc([[[i % 500, i % 300] for i in range(1_000_000)]]))
    err = error_of(text)
    assert "document too large" in str(err)


def test_deeply_nested_json_is_a_planner_error() -> None:
    assert "nested too deeply" in str(error_of("[" * 200_000 + "]" * 200_000))


def test_non_utf8_bytes() -> None:
    assert "not UTF-8" in str(error_of(b'{"units": "\xff"}'))
