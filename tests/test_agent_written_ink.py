"""The written-ink raster the agent reports: geometry, orientation, size on the wire."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from job_traces import recorded_trace

from bus.codec import decode, encode
from bus.messages import JobAssignment, WrittenInk
from planner.board import BoardFrame
from showfile import load_show
from vehicle_agent.jobs import job_metrics, prepare_job
from vehicle_agent.setup import vehicle_setup
from vehicle_agent.trace import JobTrace
from vehicle_agent.written_ink import (
    MAX_SIDE_PX,
    ink_extent_m,
    ink_pixels,
    written_ink,
    written_ink_of_trace,
)

AREA_M = (1.2, 1.2)
SHOWS = Path(__file__).resolve().parents[1] / "shows"


def pixel_of(ink: WrittenInk, x_m: float, y_m: float) -> tuple[int, int]:
    """(row, column) of the pixel holding board point (x, y); row 0 at the top."""
    x_min, y_min, x_max, y_max = ink.extent_m_board
    col = int((x_m - x_min) / (x_max - x_min) * ink.width_px)
    row = int((y_max - y_m) / (y_max - y_min) * ink.height_px)
    return row, col


def line(a: tuple[float, float], b: tuple[float, float], n: int = 200) -> np.ndarray:
    return np.linspace(a, b, n)


def test_a_straight_stroke_inks_its_band_and_nothing_else() -> None:
    width = 0.03
    tip = line((-0.3, 0.2), (0.3, 0.2))
    ink = written_ink(tip, np.full(200, width), np.ones(200, bool), AREA_M)
    pixels = ink_pixels(ink)
    assert pixels.shape == (ink.height_px, ink.width_px) == (MAX_SIDE_PX, MAX_SIDE_PX)
    pixel_m = (ink.extent_m_board[2] - ink.extent_m_board[0]) / ink.width_px
    area_px = (0.6 * width + math.pi * width**2 / 4) / pixel_m**2
    edge_px = 2 * (0.6 + width) / pixel_m  # pixels along the outline, partly covered
    # a partly covered pixel shows when a quarter of it is ink: at most 3/4 pixel more per edge
    assert 0.9 * area_px <= pixels.sum() <= area_px + 0.75 * edge_px
    rows, cols = np.nonzero(pixels)
    top, _ = pixel_of(ink, 0.0, 0.2 + width / 2 + pixel_m)
    bottom, _ = pixel_of(ink, 0.0, 0.2 - width / 2 - pixel_m)
    _, left = pixel_of(ink, -0.3 - width / 2 - pixel_m, 0.0)
    _, right = pixel_of(ink, 0.3 + width / 2 + pixel_m, 0.0)
    assert rows.min() >= top and rows.max() <= bottom  # above the centre: the upper half
    assert cols.min() >= left and cols.max() <= right
    assert rows.max() < ink.height_px / 2
    assert pixels[pixel_of(ink, 0.0, 0.2)]


def test_the_brush_in_the_air_leaves_nothing() -> None:
    tip = line((-0.3, 0.0), (0.3, 0.0))
    contact = np.zeros(200, bool)
    contact[150:] = True  # only the last quarter touches, on the right
    ink = written_ink(tip, np.full(200, 0.02), contact, AREA_M)
    cols = np.nonzero(ink_pixels(ink))[1]
    first_touch_x = float(tip[150, 0])  # 0.152 m
    assert cols.size and cols.min() >= pixel_of(ink, first_touch_x - 0.01 - 0.01, 0.0)[1]
    assert not ink_pixels(written_ink(tip, np.full(200, 0.02), np.zeros(200, bool), AREA_M)).any()


def test_the_raster_is_a_few_kilobytes_and_survives_the_wire() -> None:
    rng = np.random.default_rng(3)
    tip = np.cumsum(rng.normal(0.0, 0.01, (3000, 2)), axis=0)
    ink = written_ink(tip, np.full(3000, 0.02), rng.random(3000) > 0.2, AREA_M)
    raw = encode(ink)
    assert len(raw) < 5_000
    back = decode(raw, WrittenInk)
    assert back == ink and np.array_equal(ink_pixels(back), ink_pixels(ink))
    assert ink.extent_m_board == ink_extent_m(AREA_M)


def test_a_wide_area_keeps_square_pixels() -> None:
    ink = written_ink(np.zeros((1, 2)), np.full(1, 0.05), np.ones(1, bool), (2.0, 0.5))
    x_min, y_min, x_max, y_max = ink.extent_m_board
    assert ink.width_px == MAX_SIDE_PX and ink.height_px < MAX_SIDE_PX / 2
    assert math.isclose((x_max - x_min) / ink.width_px, (y_max - y_min) / ink.height_px)
    assert ink_pixels(ink)[pixel_of(ink, 0.0, 0.0)]


@settings(max_examples=15, deadline=None)
@given(
    x=st.floats(-0.6, 0.6),
    y=st.floats(-0.6, 0.6),
    width=st.floats(0.02, 0.08),
)
def test_a_dot_is_inked_where_it_was_pressed(x: float, y: float, width: float) -> None:
    ink = written_ink(np.array([[x, y]]), np.array([width]), np.array([True]), AREA_M)
    pixels = ink_pixels(ink)
    assert pixels[pixel_of(ink, x, y)]
    rows, cols = np.nonzero(pixels)
    centre = pixel_of(ink, x, y)
    reach = width / 2 / ((ink.extent_m_board[2] - ink.extent_m_board[0]) / ink.width_px) + 1
    assert np.all(np.hypot(rows - centre[0], cols - centre[1]) <= reach + 1)


def trace_with_tip(tip_m_enu: np.ndarray | None) -> JobTrace:
    n = 100
    zeros = np.zeros((n, 3))
    return recorded_trace(
        job_id="j", attempt=1, t_s=np.linspace(0, 1, n), position_m_enu=zeros,
        velocity_mps_enu=zeros, reference_m_enu=zeros, pen_down=np.ones(n, bool),
        pen_contact=np.ones(n, bool), pen_tip_m_enu=tip_m_enu,
        pen_width_m=np.full(n, 0.02) if tip_m_enu is not None else None,
    )  # fmt: skip


def test_a_trace_is_pictured_in_its_boards_frame() -> None:
    frame = BoardFrame(center_m_enu=(5.0, -2.0, 0.75), yaw_rad=math.pi / 2)
    board_xy = line((0.1, 0.3), (0.4, 0.3), 100)  # right of and above the centre, on the board
    tip = frame.to_world(board_xy)
    ink = written_ink_of_trace(trace_with_tip(tip), frame.to_board, AREA_M)
    assert ink is not None
    pixels = ink_pixels(ink)
    assert pixels[pixel_of(ink, 0.25, 0.3)] and not pixels[pixel_of(ink, -0.25, 0.3)]
    assert written_ink_of_trace(trace_with_tip(None), frame.to_board, AREA_M) is None


def test_the_agents_metrics_carry_the_picture_of_the_flown_job() -> None:
    setup = vehicle_setup(load_show(SHOWS / "solo.yaml"), "uav1")
    prepared = prepare_job(setup, JobAssignment(job_id="j1", text="L"))
    s = prepared.samples
    tip = s.position_m_enu - np.array([0.0, 0.0, 0.25])  # hanging straight down onto the board
    width = np.where(s.pen_down, 0.02, 0.0)
    args = ("j1", 1, s.t_s, s.position_m_enu, s.velocity_mps_enu, s.position_m_enu, s.pen_down)
    metrics = job_metrics(setup, prepared, recorded_trace(*args, s.pen_down.copy(), tip, width))
    ink = metrics.written
    assert ink is not None and decode(encode(metrics), type(metrics)) == metrics
    pixels = ink_pixels(ink)
    on_board = setup.surface.to_surface(s.position_m_enu[s.pen_down])
    assert all(pixels[pixel_of(ink, x, y)] for x, y in on_board)  # the whole path is inked
    assert not pixels[pixel_of(ink, *(-on_board.mean(axis=0)))]  # and not the mirrored spot
    no_brush = recorded_trace(*args, None)
    assert job_metrics(setup, prepared, no_brush).written is None  # no brush data
