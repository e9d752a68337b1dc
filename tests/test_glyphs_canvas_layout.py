"""Canvas-relative layout: a drawing keeps its size and place relative to its drawing area."""

from __future__ import annotations

import numpy as np
import pytest

from planner.errors import PlannerError
from planner.glyphs import fit_to_area, parse_strokes_json


def _doc(strokes: list[list[list[float]]], canvas: tuple[float, float] | None) -> dict[str, object]:
    doc: dict[str, object] = {"units": "px", "y_axis": "down", "strokes": strokes}
    if canvas is not None:
        doc["canvas"] = {"width": canvas[0], "height": canvas[1]}
    return doc


CORNER_T = [[[20.0, 20.0], [70.0, 20.0]], [[45.0, 20.0], [45.0, 70.0]]]


def test_the_canvas_maps_onto_the_area_and_the_ink_keeps_its_place() -> None:
    glyph = parse_strokes_json(_doc(CORNER_T, (300.0, 300.0)))
    assert glyph.frame == (0.0, -300.0, 300.0, 0.0)
    laid = fit_to_area(glyph, width_m=1.2, height_m=1.2, margin_m=0.1)
    x0, y0, x1, y1 = laid.bounds()
    scale = 1.0 / 300.0  # 300 px onto the 1.0 m inside the margins
    assert x1 - x0 == pytest.approx(50 * scale) and y1 - y0 == pytest.approx(50 * scale)
    assert (x0, y1) == pytest.approx((-0.5 + 20 * scale, 0.5 - 20 * scale))  # top-left stays
    again = fit_to_area(laid, width_m=1.2, height_m=1.2, margin_m=0.1)
    assert all(np.allclose(a, b) for a, b in zip(again.strokes, laid.strokes, strict=True))


def test_without_a_canvas_the_ink_fills_the_area() -> None:
    laid = fit_to_area(parse_strokes_json(_doc(CORNER_T, None)), width_m=1.2, height_m=1.2,
                       margin_m=0.1)  # fmt: skip
    x0, _, x1, _ = laid.bounds()
    assert x1 - x0 == pytest.approx(1.0)


def test_ink_past_the_canvas_edge_widens_the_frame_and_stays_inside() -> None:
    glyph = parse_strokes_json(_doc([[[-60.0, 150.0], [300.0, 150.0]]], (300.0, 300.0)))
    laid = fit_to_area(glyph, width_m=1.2, height_m=1.2, margin_m=0.1)
    x0, _, x1, _ = laid.bounds()
    assert x0 >= -0.5 - 1e-9 and x1 <= 0.5 + 1e-9


def test_a_tap_on_a_canvas_is_refused() -> None:
    glyph = parse_strokes_json(_doc([[[150.0, 150.0], [152.0, 152.0]]], (300.0, 300.0)))
    with pytest.raises(PlannerError, match="a tap") as err:
        fit_to_area(glyph, width_m=1.2, height_m=1.2)
    assert err.value.field == "strokes"
