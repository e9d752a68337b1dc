"""The MAVLink boundary, pure parts: ENU <-> NED, attitudes, URLs, mode encodings, parsing state."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from mavsim import frames as sim_frames
from vehicle_agent.backends.mavlink.frames import (
    LocalFrame,
    attitude_enu_to_ned,
    attitude_ned_to_enu,
    euler_to_matrix,
    euler_to_quaternion,
    quaternion_to_euler,
    yaw_enu_to_ned,
)
from vehicle_agent.backends.mavlink.state import ARDUPILOT, PX4, LinkState, flavor_for
from vehicle_agent.backends.mavlink.url import LinkAddress, MavlinkUrlError, parse_mavlink_url

coord = st.floats(-100.0, 100.0)
tilt = st.floats(-1.2, 1.2)
heading = st.floats(-math.pi + 1e-6, math.pi - 1e-6)


def test_local_ned_known_answer() -> None:
    frame = LocalFrame(origin_m_enu=(-3.0, -1.2, 0.0))
    # 1 m east, 2 m north, 0.5 m up of the origin = north 2, east 1, down -0.5
    assert frame.position_to_ned((-2.0, 0.8, 0.5)) == pytest.approx((2.0, 1.0, -0.5))


@given(st.tuples(coord, coord, coord), st.tuples(coord, coord, coord))
def test_local_frame_round_trip(
    origin: tuple[float, float, float], p: tuple[float, float, float]
) -> None:
    frame = LocalFrame(origin)
    assert frame.position_from_ned(frame.position_to_ned(p)) == pytest.approx(p, abs=1e-9)


def test_level_heading_known_answers() -> None:
    # Facing north: ENU yaw +90 deg, NED yaw 0; facing east: ENU 0, NED +90 deg.
    assert attitude_enu_to_ned(0.0, 0.0, math.pi / 2) == pytest.approx((0.0, 0.0, 0.0), abs=1e-12)
    assert attitude_enu_to_ned(0.0, 0.0, 0.0) == pytest.approx((0.0, 0.0, math.pi / 2))
    assert yaw_enu_to_ned(math.pi / 2) == pytest.approx(0.0)


def test_tilt_known_answer() -> None:
    # Facing east (ENU yaw 0) with the thrust tilted towards +x (ENU pitch > 0, nose down in FLU):
    # in NED/FRD that is nose down, i.e. negative pitch, heading east.
    roll, pitch, yaw = attitude_enu_to_ned(0.0, 0.2, 0.0)
    assert (roll, pitch, yaw) == pytest.approx((0.0, -0.2, math.pi / 2))


@given(tilt, tilt, heading)
def test_attitude_conversion_is_an_involution_and_keeps_the_thrust_axis(
    roll: float, pitch: float, yaw: float
) -> None:
    ned = attitude_enu_to_ned(roll, pitch, yaw)
    back = attitude_ned_to_enu(*ned)
    r1 = np.array(euler_to_matrix(roll, pitch, yaw))
    r2 = np.array(euler_to_matrix(*back))
    np.testing.assert_allclose(r1, r2, atol=1e-9)
    # body up (FLU z) in ENU == -(body down, FRD z, in NED) mapped to ENU
    up_enu = r1[:, 2]
    down_ned = np.array(euler_to_matrix(*ned))[:, 2]
    np.testing.assert_allclose(
        up_enu, -np.array([down_ned[1], down_ned[0], -down_ned[2]]), atol=1e-9
    )


@given(tilt, tilt, heading)
def test_backend_and_simulator_agree_on_attitude_frames(
    roll: float, pitch: float, yaw: float
) -> None:
    """Two independent sides of the wire (agent and vehicle) must agree on the convention."""
    sent = euler_to_quaternion(*attitude_enu_to_ned(roll, pitch, yaw))
    received = sim_frames.attitude_ned_to_enu(*sim_frames.quaternion_to_euler(sent))
    np.testing.assert_allclose(
        np.array(euler_to_matrix(*received)), np.array(euler_to_matrix(roll, pitch, yaw)), atol=1e-9
    )


@given(tilt, tilt, heading)
def test_quaternion_round_trip(roll: float, pitch: float, yaw: float) -> None:
    q = euler_to_quaternion(roll, pitch, yaw)
    assert sum(c * c for c in q) == pytest.approx(1.0)
    np.testing.assert_allclose(
        np.array(euler_to_matrix(*quaternion_to_euler(q))),
        np.array(euler_to_matrix(roll, pitch, yaw)),
        atol=1e-9,
    )


@pytest.mark.parametrize(
    ("url", "expected"),
    [
        ("udp:127.0.0.1:14561", LinkAddress("udpout", host="127.0.0.1", port=14561)),
        ("udpout://10.0.0.2:14550", LinkAddress("udpout", host="10.0.0.2", port=14550)),
        ("udpin:0.0.0.0:14540", LinkAddress("udpin", host="0.0.0.0", port=14540)),
        ("udpin::14540", LinkAddress("udpin", host="0.0.0.0", port=14540)),
        ("tcp:localhost:5760", LinkAddress("tcp", host="localhost", port=5760)),
        ("serial:/dev/ttyACM0:921600", LinkAddress("serial", device="/dev/ttyACM0", baud=921600)),
        ("/dev/ttyUSB0", LinkAddress("serial", device="/dev/ttyUSB0", baud=57600)),
    ],
)
def test_mavlink_urls(url: str, expected: LinkAddress) -> None:
    assert parse_mavlink_url(url) == expected


@pytest.mark.parametrize("url", ["", "http://x:1", "udp:127.0.0.1", "udp:host:port", "tcp::5760",
                                 "udp:1.2.3.4:70000"])  # fmt: skip
def test_bad_mavlink_urls_say_what_is_accepted(url: str) -> None:
    with pytest.raises(MavlinkUrlError, match="mavlink_url"):
        parse_mavlink_url(url)


def test_px4_and_ardupilot_mode_encodings() -> None:
    assert flavor_for(mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA) is ARDUPILOT
    assert flavor_for(mavlink.MAV_AUTOPILOT_PX4) is PX4
    assert flavor_for(mavlink.MAV_AUTOPILOT_GENERIC) is None
    assert ARDUPILOT.offboard_mode == 4 and ARDUPILOT.mode_name(4) == "GUIDED"
    assert ARDUPILOT.set_mode_params(9) == (1.0, 9.0, 0.0)
    assert PX4.offboard_mode == 393216 and PX4.mode_name(PX4.offboard_mode) == "OFFBOARD"
    assert PX4.mode_name(PX4.land_mode) == "AUTO.LAND"
    assert PX4.set_mode_params(PX4.land_mode) == (1.0, 4.0, 6.0)
    assert PX4.mode_name(3 << 16) == "POSCTL"


def _encode(system_id: int, message: object) -> object:
    sender = mavlink.MAVLink(None, srcSystem=system_id, srcComponent=1)
    data = message.pack(sender)  # type: ignore[attr-defined]
    parser = mavlink.MAVLink(None)
    (decoded,) = parser.parse_buffer(data)
    return decoded


def test_link_state_locks_on_the_autopilot_and_ignores_others() -> None:
    enc = mavlink.MAVLink(None)
    state = LinkState()
    gcs = enc.heartbeat_encode(mavlink.MAV_TYPE_GCS, mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)
    assert state.absorb(_encode(250, gcs)) == ""
    armed_guided = enc.heartbeat_encode(
        mavlink.MAV_TYPE_QUADROTOR, mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA,
        mavlink.MAV_MODE_FLAG_SAFETY_ARMED | 1, 4, 4,
    )  # fmt: skip
    assert state.absorb(_encode(7, armed_guided)) == "HEARTBEAT"
    assert (state.system_id, state.armed, state.custom_mode, state.flavor) == (
        7,
        True,
        4,
        ARDUPILOT,
    )
    assert state.absorb(_encode(8, enc.local_position_ned_encode(0, 9, 9, 9, 0, 0, 0))) == ""
    state.absorb(_encode(7, enc.local_position_ned_encode(10, 1.0, 2.0, -0.5, 0.1, 0, 0)))
    assert state.position_ned == pytest.approx((1.0, 2.0, -0.5))
    state.absorb(_encode(7, enc.statustext_encode(2, b"PreArm: Need Position Estimate")))
    assert state.take_texts() == [(2, "PreArm: Need Position Estimate")]
    # an ACK addressed to another ground station (the pilot's) is not ours
    state.absorb(_encode(7, enc.command_ack_encode(176, 0, 0, 0, 250, 190)))
    state.absorb(_encode(7, enc.command_ack_encode(400, 4, 0, 0, 255, 191)))
    assert list(state.acks) == [(400, 4)]
