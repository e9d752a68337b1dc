"""The writing surface of every kind: frames that a reader sees right way up."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from planner.board import BoardFrame
from vehicles.surface import Surface

coords = st.floats(-50.0, 50.0, allow_nan=False)
yaws = st.floats(-math.pi, math.pi, allow_nan=False)
orientations = st.sampled_from(["horizontal", "vertical", "floor"])


@given(orientations, coords, coords, coords, yaws, coords, coords, coords)
def test_world_round_trip(orientation, cx, cy, cz, yaw, x, y, standoff):
    surface = Surface.of(orientation, (cx, cy, cz), yaw)
    world = surface.to_world(np.array([[x, y]]), standoff)
    local = surface.to_local(world)
    assert np.allclose(local[0], [x, y, standoff], atol=1e-9)


@given(yaws, coords, coords)
def test_horizontal_matches_the_airshow_board(yaw, x, y):
    board = BoardFrame(center_m_enu=(1.0, -2.0, 0.7), yaw_rad=yaw)
    surface = Surface.of("horizontal", (1.0, -2.0, 0.7), yaw)
    xy = np.array([[x, y]])
    assert np.allclose(surface.to_world(xy), board.to_world(xy), atol=1e-9)


def test_a_wall_faces_its_writer_and_reads_upright():
    wall = Surface.of("vertical", (0.0, 3.0, 1.5), 0.0)
    assert np.allclose(wall.normal_enu, [0.0, -1.0, 0.0])  # the vehicle stands south of it
    top_right = wall.to_world(np.array([[0.5, 0.4]]), 0.2)[0]
    assert np.allclose(top_right, [0.5, 2.8, 1.9])  # right is east, up is up, 0.2 m off the wall


def test_floor_normal_is_up():
    assert np.allclose(Surface.of("floor", (0.0, 0.0, 0.1), 1.0).normal_enu, [0.0, 0.0, 1.0])
