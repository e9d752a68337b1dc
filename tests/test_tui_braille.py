"""tui.braille, tui.preview, tui.settings geometry and tui.format: known answers and properties."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from hypothesis import given
from hypothesis import strategies as st

from bus.messages import JobMetrics, JobState
from tui import format as fmt
from tui.braille import BrailleCanvas, apply_transform, fit_transform
from tui.preview import render_preview, render_strokes, stroke_polylines
from tui.rows import QueueRow
from tui.settings import BoardGeometry

DATA = Path(__file__).parent / "data"


def test_dots_map_to_unicode_braille_numbering() -> None:
    canvas = BrailleCanvas(1, 1)
    canvas.set(0, 0)  # dot 1
    assert canvas.lines() == ["⠁"]
    canvas.set(1, 3)  # dot 8
    assert canvas.lines() == [chr(0x2800 + 0x01 + 0x80)]
    full = BrailleCanvas(1, 1)
    for x in range(2):
        for y in range(4):
            full.set(x, y)
    assert full.lines() == ["⣿"]


def test_drawing_outside_is_clipped_silently() -> None:
    canvas = BrailleCanvas(2, 1)
    canvas.set(-1, 0)
    canvas.set(4, 0)
    canvas.line(-100.0, 2.0, 100.0, 2.0)
    assert canvas.lines() == ["⠤⠤"]  # only the visible part of the long line


@given(st.integers(0, 19), st.integers(0, 11), st.integers(0, 19), st.integers(0, 11))
def test_a_line_joins_its_ends_without_leaving_their_box(
    x0: int, y0: int, x1: int, y1: int
) -> None:
    canvas = BrailleCanvas(10, 3)
    canvas.line(x0, y0, x1, y1)
    assert canvas.get(x0, y0) and canvas.get(x1, y1)
    on = [(x, y) for x in range(20) for y in range(12) if canvas.get(x, y)]
    assert all(min(x0, x1) <= x <= max(x0, x1) and min(y0, y1) <= y <= max(y0, y1) for x, y in on)
    assert len(on) == max(abs(x1 - x0), abs(y1 - y0)) + 1  # connected, one dot per step


def test_the_highest_layer_in_a_cell_gives_its_style() -> None:
    canvas = BrailleCanvas(2, 1, layers=2)
    canvas.set(0, 0, layer=0)
    canvas.set(1, 1, layer=1)
    canvas.set(2, 0, layer=0)
    assert canvas.cell(0, 0) == (chr(0x2800 + 0x01 + 0x10), 1)
    text = canvas.to_text(["blue", "red"])
    assert text.plain == "⠑⠁"
    assert [(span.start, span.end, str(span.style)) for span in text.spans] == [
        (0, 1, "red"),
        (1, 2, "blue"),
    ]


def test_fit_transform_centres_and_keeps_the_aspect_ratio() -> None:
    transform = fit_transform((-1.0, -0.5, 1.0, 0.5), 41, 41, margin_dots=0)
    assert apply_transform(transform, -1.0, 0.5) == pytest.approx((0.0, 10.0))  # y up: top row
    assert apply_transform(transform, 1.0, -0.5) == pytest.approx((40.0, 30.0))
    assert apply_transform(transform, 0.0, 0.0) == pytest.approx((20.0, 20.0))


def test_board_frame_follows_yaw_and_orientation() -> None:
    board = BoardGeometry("b", center_m_enu=(1.0, 2.0, 0.5), yaw_deg=90.0)
    assert board.to_board((1.0, 3.0, 0.9)) == pytest.approx((1.0, 0.0))  # north is board +x
    wall = BoardGeometry("w", center_m_enu=(0.0, 0.0, 1.5), orientation="vertical")
    assert wall.to_board((0.3, -0.2, 2.0)) == pytest.approx((0.3, 0.5))  # up is picture up


def test_tablet_strokes_with_y_down_are_drawn_upright() -> None:
    document = json.loads((DATA / "handwritten_S_px.json").read_text())
    lines, y_up = stroke_polylines(document)
    assert not y_up and len(lines) == 1 and len(lines[0]) == 50
    text = render_strokes(document, 8, 4)
    assert text is not None
    rows = text.plain.split("\n")
    # The S starts at its top right (x 213, y 63 with y down) and ends at its bottom left.
    flipped = render_strokes({**document, "y_axis": "up"}, 8, 4)
    assert rows != flipped.plain.split("\n")
    assert rows[0].strip() and rows[-1].strip()


def test_metre_strokes_fill_the_preview() -> None:
    document = json.loads((DATA / "l_tick_m_up.json").read_text())
    text = render_strokes(document, 10, 5)
    assert text is not None
    rows = text.plain.split("\n")
    assert len(rows) == 5 and all(len(r) == 10 for r in rows)
    assert rows[0][0] != " " and rows[-1][0] != " "  # the L's upright at the left edge


def test_preview_falls_back_to_text_and_survives_garbage() -> None:
    assert render_strokes({"strokes": [[["a", None]], 5]}, 4, 2) is None
    assert render_strokes(None, 4, 2) is None
    assert render_preview("永", {"strokes": "nope"}, "永", 6, 3).plain == "永"
    assert render_preview(None, None, "drawing (3 strokes)", 6, 3).plain == "drawing (3 strokes)"


@pytest.mark.parametrize(
    ("seconds", "shown"),
    [(None, "-"), (0.4, "0s"), (59.6, "1m00s"), (125, "2m05s"), (3725, "1h02m")],
)
def test_durations_read_short(seconds: float | None, shown: str) -> None:
    assert fmt.duration(seconds) == shown


def test_job_details_name_what_matters_in_each_section() -> None:
    base = dict(
        job_id="j1", label="永", kind="text", client_id="kiosk", created_at_s=0.0, updated_at_s=0.0
    )
    queued = JobState(state="queued", queue_position=2, eta_s=95.0, **base)  # type: ignore[arg-type]
    done = JobState(
        state="done",
        **base,
        metrics=JobMetrics(  # type: ignore[arg-type]
            rmse_pen_down_m=0.0123, rmse_m=0.02, max_error_m=0.05, iou=0.834, duration_s=30.0
        ),
    )
    assert fmt.job_detail(QueueRow("queued", queued)) == "#2 ETA 1m35s"
    assert fmt.job_detail(QueueRow("done", done)) == "RMSE 1.2cm IoU 0.83"
    assert fmt.progress(0.5, 4) == "██░░  50%"
    assert math.isclose(len(fmt.short_id("abcdefghijk")), 8)
