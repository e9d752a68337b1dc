"""fit_to_area: uniform scale, centred, inside the area; the Glyph type's own checks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.errors import PlannerError
from planner.glyphs import Glyph, fit_to_area, glyphs_equal, text_glyph

coord = st.floats(min_value=-1e4, max_value=1e4, allow_subnormal=False)


@st.composite
def glyphs(draw: st.DrawFn) -> Glyph:
    n_strokes = draw(st.integers(1, 4))
    strokes = []
    for _ in range(n_strokes):
        pts = draw(st.lists(st.tuples(coord, coord), min_size=2, max_size=8))
        arr = np.array(pts, dtype=np.float64)
        if np.ptp(arr, axis=0).max() == 0.0:
            arr[1, 0] += 1.0  # at least 2 distinct points, like every real source
        strokes.append(arr)
    units = draw(st.sampled_from(["px", "m", "em"]))
    return Glyph(tuple(strokes), (None,) * n_strokes, units, "random", "test")


sizes = st.floats(min_value=0.05, max_value=20.0)


@settings(max_examples=150, deadline=None)
@given(glyph=glyphs(), width=sizes, height=sizes, margin_frac=st.floats(0.0, 0.45))
def test_fit_keeps_aspect_and_stays_inside(
    glyph: Glyph, width: float, height: float, margin_frac: float
) -> None:
    margin = margin_frac * min(width, height)
    fitted = fit_to_area(glyph, width_m=width, height_m=height, margin_m=margin)
    assert fitted.units == "m"
    x0, y0, x1, y1 = glyph.bounds()
    fx0, fy0, fx1, fy1 = fitted.bounds()
    tol = 1e-9 * max(width, height)
    # inside the area less margins, centred on (0, 0)
    assert fx0 >= -width / 2 + margin - tol and fx1 <= width / 2 - margin + tol
    assert fy0 >= -height / 2 + margin - tol and fy1 <= height / 2 - margin + tol
    assert fx0 + fx1 == pytest.approx(0.0, abs=tol)
    assert fy0 + fy1 == pytest.approx(0.0, abs=tol)
    # one uniform scale maps every point: aspect ratio kept, shape unchanged
    w_in, h_in = width - 2 * margin, height - 2 * margin
    extents = [(x1 - x0, w_in), (y1 - y0, h_in)]
    scale = min(inner / ext for ext, inner in extents if ext > 0)
    centre = np.array([(x0 + x1) / 2, (y0 + y1) / 2])
    for before, after in zip(glyph.strokes, fitted.strokes, strict=True):
        np.testing.assert_allclose(after, (before - centre) * scale, rtol=1e-9, atol=tol)
    # and it is the largest such scale: one side touches the inner area
    assert max((fx1 - fx0) / w_in, (fy1 - fy0) / h_in) == pytest.approx(1.0, rel=1e-9)


def test_fit_wide_word_is_limited_by_width() -> None:
    fitted = fit_to_area(text_glyph("HELLO"), width_m=2.0, height_m=2.0, margin_m=0.1)
    x0, y0, x1, y1 = fitted.bounds()
    assert (x0, x1) == pytest.approx((-0.9, 0.9))
    assert y1 - y0 < 1.8
    assert fitted.label == "HELLO"
    assert fitted.source == "hershey:futural"


def test_fit_vertical_line_uses_its_height() -> None:
    fitted = fit_to_area(text_glyph("I"), width_m=1.0, height_m=3.0)
    np.testing.assert_allclose(fitted.strokes[0], [[0.0, 1.5], [0.0, -1.5]])


def test_fit_keeps_times() -> None:
    times = np.array([0.0, 0.5])
    g = Glyph((np.array([[0.0, 0.0], [2.0, 1.0]]),), (times,), "px", "t", "strokes-json")
    fitted = fit_to_area(g, width_m=1.0, height_m=1.0)
    assert fitted.times_s[0] is not None
    np.testing.assert_array_equal(fitted.times_s[0], times)


@pytest.mark.parametrize(
    ("kwargs", "field"),
    [
        ({"width_m": 0.0, "height_m": 1.0}, "width_m"),
        ({"width_m": 1.0, "height_m": -2.0}, "height_m"),
        ({"width_m": math.nan, "height_m": 1.0}, "width_m"),
        ({"width_m": 1.0, "height_m": math.inf}, "height_m"),
        ({"width_m": True, "height_m": 1.0}, "width_m"),
        ({"width_m": 1.0, "height_m": 1.0, "margin_m": -0.1}, "margin_m"),
        ({"width_m": 1.0, "height_m": 2.0, "margin_m": 0.5}, "margin_m"),
    ],
)
def test_fit_rejects_bad_sizes(kwargs: dict[str, float], field: str) -> None:
    with pytest.raises(PlannerError) as info:
        fit_to_area(text_glyph("A"), **kwargs)
    assert info.value.field == field


def test_fit_rejects_glyph_without_extent() -> None:
    g = Glyph((np.array([[1.0, 1.0], [1.0, 1.0]]),), (None,), "m", "dot", "test")
    with pytest.raises(PlannerError, match="no extent"):
        fit_to_area(g, width_m=1.0, height_m=1.0)
    tiny = Glyph((np.array([[0.0, 0.0], [5e-324, 0.0]]),), (None,), "m", "speck", "test")
    with pytest.raises(PlannerError, match="too small"):
        fit_to_area(tiny, width_m=10.0, height_m=1.0)


@pytest.mark.parametrize(
    ("strokes", "times", "units", "words"),
    [
        ((), (), "m", "at least one stroke"),
        ((np.zeros((2, 3)),), (None,), "m", "shape (n, 2)"),
        ((np.zeros((1, 2)),), (None,), "m", "at least 2 points"),
        ((np.array([[0.0, 0.0], [np.nan, 1.0]]),), (None,), "m", "not finite"),
        ((np.array([[0.0, 0.0], [1.0, 1.0]]),), (None,), "inch", "unknown units"),
        ((np.array([[0.0, 0.0], [1.0, 1.0]]),), (None, None), "m", "2 time arrays for 1"),
        ((np.array([[0.0, 0.0], [1.0, 1.0]]),), (np.array([1.0, 0.0]),), "m", "non-decreasing"),
        ((np.array([[0.0, 0.0], [1.0, 1.0]]),), (np.array([1.0]),), "m", "shape (2,)"),
    ],
)
def test_glyph_validates_itself(
    strokes: tuple[np.ndarray, ...], times: tuple[np.ndarray | None, ...], units: str, words: str
) -> None:
    with pytest.raises(PlannerError, match=words.replace("(", r"\(").replace(")", r"\)")):
        Glyph(strokes, times, units, "x", "test")


def test_glyph_copies_its_input() -> None:
    pts = np.array([[0.0, 0.0], [1.0, 1.0]])
    g = Glyph((pts,), (None,), "m", "x", "test")
    pts[0, 0] = 9.0
    assert g.strokes[0][0, 0] == 0.0
    assert glyphs_equal(g, Glyph((np.array([[0.0, 0.0], [1.0, 1.0]]),), (None,), "m", "x", "test"))
    assert not glyphs_equal(g, fit_to_area(g, width_m=1.0, height_m=1.0))


def test_laying_out_keeps_the_pen_widths_of_each_point() -> None:
    import numpy as np

    from planner.glyphs import Glyph, fit_to_area

    stroke = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 5.0]])
    widths = np.array([0.005, 0.01, 0.012])
    glyph = Glyph((stroke,), (None,), "px", "w", "test", widths_m=(widths,))
    fitted = fit_to_area(glyph, width_m=1.0, height_m=1.0)
    np.testing.assert_array_equal(fitted.widths_m[0], widths)
