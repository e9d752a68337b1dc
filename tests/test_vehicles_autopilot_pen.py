"""The brush room's pen of an autopilot-flown quadrotor: the simulated brush, from a pose."""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
import pytest

from vehicles.quadrotor_brush.autopilot_pen import BrushPen
from vehicles.quadrotor_brush.brush import brush_state
from vehicles.quadrotor_brush.params import BrushParams
from vehicles.registry import vehicle_kind

if TYPE_CHECKING:
    from vehicles.kind import Mat3

BOARD_HEIGHT_M = 0.4
PARAMS = BrushParams()


def _rotation(roll_rad: float, pitch_rad: float, yaw_rad: float) -> Mat3:
    """Body (FLU) -> ENU of Z-Y-X Euler angles, by rows."""
    cr, sr = math.cos(roll_rad), math.sin(roll_rad)
    cp, sp = math.cos(pitch_rad), math.sin(pitch_rad)
    cy, sy = math.cos(yaw_rad), math.sin(yaw_rad)
    rx = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    ry = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    rz = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    r = rz @ ry @ rx
    return (
        (float(r[0, 0]), float(r[0, 1]), float(r[0, 2])),
        (float(r[1, 0]), float(r[1, 1]), float(r[1, 2])),
        (float(r[2, 0]), float(r[2, 1]), float(r[2, 2])),
    )


@pytest.mark.parametrize(
    ("height_above_board_m", "touches"),
    [(PARAMS.length_m - 0.01, True), (PARAMS.length_m + 0.05, False)],
)
def test_the_pen_of_a_tilted_pose_is_the_worlds_brush(
    height_above_board_m: float, touches: bool
) -> None:
    rotation = _rotation(0.15, -0.1, 0.7)
    position = (0.3, -0.2, BOARD_HEIGHT_M + height_above_board_m)
    reading = BrushPen(PARAMS, BOARD_HEIGHT_M).read(position, rotation)
    body_z_enu = np.array(rotation)[:, 2]  # the body z axis: a column, not a row
    state = brush_state(PARAMS, np.array([position]), body_z_enu[None, :], BOARD_HEIGHT_M)
    assert reading.contact is touches is bool(state.contact[0])
    assert reading.tip_m_enu == tuple(state.tip_m_enu[0])
    assert reading.width_m == float(state.width_m[0])
    if touches:
        assert reading.tip_m_enu[2] == pytest.approx(BOARD_HEIGHT_M)
        assert reading.width_m > PARAMS.tip_width_m
    else:
        assert reading.width_m == 0.0
        assert reading.tip_m_enu == pytest.approx(tuple(position - PARAMS.length_m * body_z_enu))


def test_a_tilt_swings_the_tip_against_the_lean() -> None:
    # rolled 0.2 rad about the body x axis (facing east): the top leans to -y, the tip to +y
    lean_rad = 0.2
    free = PARAMS.length_m + 0.05
    reading = BrushPen(PARAMS, 0.0).read((0.0, 0.0, free), _rotation(lean_rad, 0.0, 0.0))
    assert not reading.contact
    expected = (
        0.0,
        PARAMS.length_m * math.sin(lean_rad),
        free - PARAMS.length_m * math.cos(lean_rad),
    )
    assert reading.tip_m_enu == pytest.approx(expected, abs=1e-12)


def test_the_kinds_autopilot_world_is_its_simulated_worlds_brush_and_mocap() -> None:
    kind = vehicle_kind("quadrotor-brush")
    settings = kind.settings(None, None)
    world = kind.autopilot_world(settings)
    simulated = settings.flight.world
    assert world is not None
    assert world.pen == BrushPen(simulated.brush, simulated.board_height_m)
    assert (world.mocap_latency_s, world.mocap_noise_std_m) == (
        simulated.mocap.latency_s,
        simulated.mocap.noise_std_m,
    )
