"""Strokes documents with a per-point line width ``w`` in metres."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from planner.errors import PlannerError
from planner.glyphs import parse_strokes_json
from planner.glyphs.glyph import Glyph, concat_glyphs

SCHEMA = Path(__file__).resolve().parents[1] / "docs" / "strokes.schema.json"


def doc(strokes: Any) -> dict[str, Any]:
    return {"units": "m", "y_axis": "up", "strokes": strokes}


def test_widths_are_read_per_point_and_follow_merged_points() -> None:
    g = parse_strokes_json(
        doc(
            [
                [
                    {"x": 0.0, "y": 0.0, "w": 0.006},
                    {"x": 0.0, "y": 0.0, "w": 0.009},
                    {"x": 0.1, "y": 0.0, "w": 0.012},
                ]
            ]
        )
    )
    np.testing.assert_array_equal(g.strokes[0], [[0.0, 0.0], [0.1, 0.0]])
    np.testing.assert_array_equal(g.widths_m[0], [0.006, 0.012])


def test_object_points_with_time_and_pressure() -> None:
    g = parse_strokes_json(
        doc(
            [
                [
                    {"x": 1, "y": 2, "t": 0.0, "pressure": 0.5, "w": 0.01},
                    {"x": 2, "y": 2, "t": 0.1, "pressure": 0.7, "w": 0.01},
                ]
            ]
        )
    )
    assert g.times_s[0] is not None
    np.testing.assert_array_equal(g.times_s[0], [0.0, 0.1])


def test_documents_without_widths_have_none() -> None:
    g = parse_strokes_json(doc([[[0.0, 0.0], [0.1, 0.0]]]))
    assert g.widths_m == ()


@pytest.mark.parametrize(
    ("point", "message"),
    [
        (
            {"x": 0.1, "y": 0.0, "w": -0.01},
            r"stroke 0, point 1: .*w must be in \(0, 1\] m, got -0.01",
        ),
        ({"x": 0.1, "y": 0.0, "w": "wide"}, r"point 1: .*w must be a finite number in metres"),
        ({"x": 0.1, "y": 0.0}, r"point 1: .*has a width w; every point must then be the same"),
        ({"x": 0.1, "w": 0.01}, r"point 1: .*a point object needs y"),
        ({"x": 0.1, "y": 0.0, "w": 0.01, "z": 1}, r"point 1: .*unknown point key 'z'"),
        ({"x": 0.1, "y": 0.0, "pressure": 1, "w": 0.01}, r"point 1: .*pressure needs t"),
    ],
)
def test_bad_widths_name_stroke_and_point(point: dict[str, Any], message: str) -> None:
    with pytest.raises(PlannerError, match=message):
        parse_strokes_json(doc([[{"x": 0.0, "y": 0.0, "w": 0.01}, point]]))


def test_glyph_checks_widths_and_concat_keeps_them() -> None:
    line = np.array([[0.0, 0.0], [1.0, 0.0]])
    with pytest.raises(PlannerError, match="point 1: width must be finite and positive"):
        Glyph((line,), (None,), "m", "x", "test", widths_m=(np.array([0.01, 0.0]),))
    a = Glyph((line,), (None,), "m", "a", "test", widths_m=(np.array([0.01, 0.02]),))
    b = Glyph((line,), (None,), "m", "b", "test")
    joined = concat_glyphs([a, b], label="ab", source="test")
    assert joined.widths_m[1] is None
    np.testing.assert_array_equal(joined.widths_m[0], [0.01, 0.02])


def test_schema_describes_object_points_with_w() -> None:
    schema = json.loads(SCHEMA.read_text())
    point = schema["$defs"]["point"]
    objects = [alt for alt in point["oneOf"] if alt.get("type") == "object"]
    assert objects and objects[0]["properties"]["w"]["exclusiveMinimum"] == 0
