"""A MAVLink vehicle's pen: its kind's pen model read from the ATTITUDE (NED, FRD), contact only
over its board, as ``create_backend`` sets it up from the show."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from showfile import load_show
from vehicle_agent.backends.mavlink.create import create_backend
from vehicle_agent.backends.mavlink.pen import PenOverBoard
from vehicle_agent.setup import vehicle_setup
from vehicles.quadrotor_brush.autopilot_pen import BrushPen
from vehicles.quadrotor_brush.params import BrushParams

SHOWS = Path(__file__).resolve().parents[1] / "shows"
PARAMS = BrushParams()


def test_a_roll_to_the_right_facing_north_swings_the_brush_west() -> None:
    # NED attitude: heading north, right (east) wing down by 0.2 rad; the body's top leans east
    roll_rad = 0.2
    free_m = PARAMS.length_m + 0.05
    pen = PenOverBoard(BrushPen(PARAMS, 0.0))
    reading = pen.read((0.0, 0.0, free_m), (roll_rad, 0.0, 0.0))
    lever_m = PARAMS.length_m
    expected = (-lever_m * math.sin(roll_rad), 0.0, free_m - lever_m * math.cos(roll_rad))
    assert reading.tip_m_enu == pytest.approx(expected, abs=1e-12)
    assert not reading.contact and reading.width_m == 0.0


def test_contact_counts_over_the_board_only() -> None:
    pen = BrushPen(PARAMS, 0.0)
    pressed = (0.1, 0.0, PARAMS.length_m - 0.01)
    attitude = (0.05, -0.1, 1.0)
    anywhere = PenOverBoard(pen).read(pressed, attitude)
    over = PenOverBoard(pen, lambda tip: tip[0] > 0.0).read(pressed, attitude)
    off = PenOverBoard(pen, lambda tip: tip[0] < 0.0).read(pressed, attitude)
    assert anywhere.contact and anywhere.width_m > 0.0
    assert over == anywhere
    assert (off.tip_m_enu, off.width_m, off.contact) == (anywhere.tip_m_enu, 0.0, False)


def test_the_backend_carries_the_kinds_pen_over_its_board_and_its_mocap() -> None:
    setup = vehicle_setup(load_show(SHOWS / "rehearsal-mavlink.yaml"), "uav2")
    world = setup.kind.autopilot_world(setup.settings)
    assert world is not None
    backend = create_backend(setup)
    s = backend.settings
    assert (s.mocap_latency_s, s.mocap_noise_std_m) == (
        world.mocap_latency_s,
        world.mocap_noise_std_m,
    )
    assert backend.pen is not None and backend.pen.pen == world.pen
    board_z_m = setup.surface.origin_m_enu[2]  # b2: centred at (-1, 0), 1.4 m square
    low_m = board_z_m + setup.settings.flight.world.brush.length_m - 0.01
    assert backend.pen.read((-1.0, 0.0, low_m), (0.0, 0.0, 0.0)).contact
    assert not backend.pen.read((-1.0, 0.8, low_m), (0.0, 0.0, 0.0)).contact
