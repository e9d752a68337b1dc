"""Brush on a linear bearing and ink on the board: widths, contact, footprints, IoU."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sim.errors import SimError
from sim.ink import InkCanvas, RasterSpec, iou
from sim.params import MocapParams
from vehicles.quadrotor_brush.brush import brush_state
from vehicles.quadrotor_brush.dynamics import InnerLoopCommand
from vehicles.quadrotor_brush.params import BrushParams, WorldParams
from vehicles.quadrotor_brush.world import World

BRUSH = BrushParams()


def test_nominal_press_gives_the_nominal_width() -> None:
    p = np.array([[0.0, 0.0, BRUSH.write_height_m], [0.0, 0.0, BRUSH.length_m + 0.01]])
    up = np.tile([0.0, 0.0, 1.0], (2, 1))
    state = brush_state(BRUSH, p, up, 0.0)
    assert state.contact.tolist() == [True, False]
    assert state.press_m[0] == pytest.approx(BRUSH.nominal_press_m)
    assert state.width_m[0] == pytest.approx(BRUSH.nominal_width_m)
    assert state.width_m[1] == 0.0
    assert state.tip_m_enu[0, 2] == pytest.approx(0.0)


def test_width_grows_with_press_and_the_stop_is_flagged() -> None:
    heights = BRUSH.length_m - np.array([0.005, 0.010, 0.030, BRUSH.travel_m + 0.01])
    p = np.stack([np.zeros(4), np.zeros(4), heights], axis=1)
    state = brush_state(BRUSH, p, np.tile([0.0, 0.0, 1.0], (4, 1)), 0.0)
    assert np.all(np.diff(state.width_m[:3]) > 0.0)
    assert state.bottomed.tolist() == [False, False, False, True]


def test_a_tilted_body_moves_the_tip_opposite_to_the_lean() -> None:
    tilt = 0.1  # thrust leaning towards +x
    axis = np.array([[math.sin(tilt), 0.0, math.cos(tilt)]])
    p = np.array([[0.0, 0.0, BRUSH.write_height_m]])
    state = brush_state(BRUSH, p, axis, 0.0)
    assert state.contact[0]
    assert state.tip_m_enu[0, 0] < -0.03
    assert state.tip_m_enu[0, 2] == pytest.approx(0.0, abs=1e-12)


def test_board_contact_does_not_change_the_flight() -> None:
    """The bearing slides freely: a brush that touches and one that does not fly the same."""
    quiet = MocapParams(noise_std_m=0.0)
    touching = World(WorldParams(mocap=quiet), [(0.0, 0.0, 0.335)], seed=1)
    short = WorldParams(mocap=quiet, brush=BrushParams(length_m=0.2, travel_m=0.05))
    free = World(short, [(0.0, 0.0, 0.335)], seed=1)
    hover = touching.hover_throttle
    contacts = 0
    for k in range(200):
        throttle = hover * (1.0 + 0.005 * math.sin(0.2 * k))
        for world in (touching, free):
            world.step(InnerLoopCommand(throttle, np.zeros(1), np.zeros(1), np.zeros(1)))
        contacts += int(touching.brush().contact[0])
        assert not free.brush().contact[0]
    assert contacts > 150
    assert np.array_equal(touching.state.position_m_enu, free.state.position_m_enu)
    assert np.array_equal(touching.state.velocity_mps_enu, free.state.velocity_mps_enu)


def canvas(pixel_m: float = 0.001) -> InkCanvas:
    return InkCanvas(RasterSpec.covering(np.array([[-0.3, -0.3], [0.3, 0.3]]), pixel_m=pixel_m))


def line(offset_m: float = 0.0, n: int = 201) -> np.ndarray:
    x = np.linspace(-0.2, 0.2, n)
    return np.stack([x, np.full(n, offset_m)], axis=1)


def test_swept_footprint_covers_a_capsule() -> None:
    ink = canvas()
    pts = line()
    ink.paint_path(pts, np.full(len(pts), 0.02), np.ones(len(pts), dtype=bool))
    area = np.count_nonzero(ink.pixels) * 1e-6
    assert area == pytest.approx(0.4 * 0.02 + math.pi * 0.01**2, rel=0.02)


def test_one_long_segment_paints_like_many_short_ones() -> None:
    a, b = canvas(), canvas()
    a.paint_capsules(np.array([[-0.2, 0.0]]), np.array([[0.2, 0.05]]), np.array([0.01]))
    pts = np.stack([np.linspace(-0.2, 0.2, 400), np.linspace(0.0, 0.05, 400)], axis=1)
    b.paint_path(pts, np.full(400, 0.02), np.ones(400, dtype=bool))
    assert iou(a.pixels, b.pixels) > 0.99


def test_a_single_touch_paints_a_dot() -> None:
    ink = canvas()
    inked = np.array([False, True, False])
    ink.paint_path(np.zeros((3, 2)), np.full(3, 0.02), inked)
    assert np.count_nonzero(ink.pixels) * 1e-6 == pytest.approx(math.pi * 0.01**2, rel=0.03)


def test_iou_is_one_against_itself_and_drops_with_an_offset() -> None:
    pts = line()
    down = np.ones(len(pts), dtype=bool)
    target, same, shifted = canvas(), canvas(), canvas()
    for ink, path in ((target, pts), (same, pts.copy()), (shifted, line(0.005))):
        ink.paint_path(path, np.full(len(path), 0.02), down)
    assert iou(same.pixels, target.pixels) == 1.0
    # two 20 mm bands 5 mm apart overlap (20 - 5) / (20 + 5) of their union
    assert iou(shifted.pixels, target.pixels) == pytest.approx(15.0 / 25.0, abs=0.03)


def test_pen_up_samples_paint_nothing_and_nothing_written_scores_zero() -> None:
    ink = canvas()
    pts = line()
    ink.paint_path(pts, np.full(len(pts), 0.02), np.zeros(len(pts), dtype=bool))
    assert not ink.pixels.any()
    assert iou(ink.pixels, canvas().pixels) == 0.0  # nothing against nothing: no agreement seen
    target = canvas()
    target.paint_path(pts, np.full(len(pts), 0.02), np.ones(len(pts), dtype=bool))
    assert iou(ink.pixels, target.pixels) == 0.0
    with pytest.raises(SimError, match="target"):
        iou(ink.pixels, canvas(0.002).pixels)
