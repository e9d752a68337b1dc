"""mavsim's reading of guided setpoints and parameters, alone (no sockets): ArduCopter's answers."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from mavsim.guided import climb_rate_mps
from mavsim.params import INT32, REAL32, Flavor, ParamTable
from mavsim.wire import GuidedSetpoint, Pose, Stop, decode_position_target, px4_view
from vehicle_agent.backends.mavlink.params import decode_value, encode_value

POSE = Pose(home_m_enu=(1.0, 2.0, 0.0), position_m_enu=(1.0, 2.0, 1.0), yaw_rad=0.0)


def message(mask: int, frame: int = 1, **fields: float) -> SimpleNamespace:
    values = {"x": 0.5, "y": 0.0, "z": -1.0, "vx": 0.2, "vy": 0.0, "vz": 0.0, "afx": 0.0,
              "afy": 0.0, "afz": 0.0, "yaw": math.pi / 2, "yaw_rate": 0.0, **fields}  # fmt: skip
    return SimpleNamespace(coordinate_frame=frame, type_mask=mask, **values)


@pytest.mark.parametrize(
    ("mask", "arducopter", "px4"),
    [
        (0x0C00, "posvelaccel", "posvelaccel"),
        (0x0800, "posvelaccel", "posvelaccel"),
        (0x0DF8, "pos", "pos"),
        (0x09F8, "pos", "pos"),
        (0x0FF8, "pos", "pos"),  # the force bit is harmless while acceleration is ignored
        (0x0FC7, "velaccel", "velaccel"),
        (0x0E00, "stop", "ignored"),  # a force with acceleration: not supported
        (0x0C38, "stop", "posvelaccel"),  # position + acceleration: ArduCopter has no such mode
        (0x0FFF, "stop", "ignored"),
    ],
)
def test_type_masks_are_read_as_the_autopilots_read_them(
    mask: int, arducopter: str, px4: str
) -> None:
    decoded = decode_position_target(message(mask), POSE)
    assert ("stop" if isinstance(decoded, Stop) else decoded.control) == arducopter
    seen = px4_view(message(mask), POSE)
    assert ("ignored" if seen is None else seen.control) == px4


def test_position_velocity_and_yaw_land_in_the_show_frame() -> None:
    decoded = decode_position_target(message(0x0800), POSE)
    assert isinstance(decoded, GuidedSetpoint)
    assert decoded.position_m_enu == pytest.approx((1.0, 2.5, 1.0))  # 0.5 m north of home
    assert decoded.velocity_mps_enu == pytest.approx((0.0, 0.2, 0.0))
    assert decoded.yaw_rad == pytest.approx(0.0)  # NED yaw pi/2 (east) = ENU 0
    assert decode_position_target(message(0x0C00), POSE).yaw_rad is None  # type: ignore[union-attr]
    offset = decode_position_target(message(0x0DF8, frame=7), POSE)
    assert offset.position_m_enu == pytest.approx((1.0, 2.5, 2.0))  # type: ignore[union-attr]


@pytest.mark.parametrize(("frame", "vx"), [(2, 0.2), (1, math.nan), (1, 2000.0)])
def test_unsupported_frames_and_insane_velocities_stop_the_vehicle(frame: int, vx: float) -> None:
    assert isinstance(decode_position_target(message(0x0C00, frame=frame, vx=vx), POSE), Stop)


def test_thrust_as_climb_rate_is_arducopters_stick() -> None:
    assert climb_rate_mps(0.5, 250.0, 150.0) == 0.0
    assert climb_rate_mps(1.0, 250.0, 150.0) == pytest.approx(2.5)
    assert climb_rate_mps(0.0, 250.0, 150.0) == pytest.approx(-1.5)
    assert climb_rate_mps(0.52, 250.0, 150.0) == pytest.approx(0.1)  # 1 kg at 19.6 N: climbs


@pytest.mark.parametrize("flavor", ["ardupilot", "px4"])
def test_parameter_values_cross_the_wire_as_each_autopilot_packs_them(flavor: Flavor) -> None:
    table = ParamTable(flavor)
    name_int = "GF_ACTION" if flavor == "px4" else "GUID_OPTIONS"
    name_float = "COM_OF_LOSS_T" if flavor == "px4" else "GUID_TIMEOUT"
    for name, value, kind in ((name_int, 5, INT32), (name_float, 0.75, REAL32)):
        raw = encode_value(flavor, value, kind)  # the agent's PARAM_SET
        assert table.set_from_link(name, raw) == value
        echoed, echoed_kind = table.encode(name)  # mavsim's PARAM_VALUE
        assert (decode_value(flavor, echoed, echoed_kind), echoed_kind) == (value, kind)
    if flavor == "px4":
        assert encode_value("px4", 5, INT32) != 5.0  # bytewise, not a cast
    frozen = ParamTable(flavor, frozen=(name_float,))
    assert frozen.set_from_link(name_float, encode_value(flavor, 0.3, REAL32)) != 0.3
