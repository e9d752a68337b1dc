"""Mocap as ODOMETRY: the velocity between poses, and each autopilot's frames, checked against
how ArduPilot and PX4 read the message back (mavsim's :func:`odometry_is_pose` and ArduPilot's
``vel = q * vel_body``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from pymavlink.dialects.v20 import ardupilotmega as mavlink

from mavsim.mocap import odometry_is_pose
from vehicle_agent.backends.mavlink.odometry import PoseVelocity, encode_odometry

MAV = mavlink.MAVLink(None, srcSystem=255, srcComponent=191)
ANGLE = st.floats(-1.2, 1.2)
SPEED = st.floats(-3.0, 3.0)


def decoded(message: mavlink.MAVLink_message) -> mavlink.MAVLink_message:
    """The message as the autopilot receives it: packed to bytes and parsed back."""
    parser = mavlink.MAVLink(None)
    return parser.decode(bytearray(message.pack(MAV)))


def rotate(q: list[float], v: tuple[float, float, float]) -> tuple[float, float, float]:
    """``v`` rotated by the unit quaternion ``q`` (w, x, y, z): q v q*."""
    w, x, y, z = q
    vx, vy, vz = v
    # t = 2 q_vec x v; v' = v + w t + q_vec x t
    tx, ty, tz = 2 * (y * vz - z * vy), 2 * (z * vx - x * vz), 2 * (x * vy - y * vx)
    return (vx + w * tx + (y * tz - z * ty), vy + w * ty + (z * tx - x * tz),
            vz + w * tz + (x * ty - y * tx))  # fmt: skip


def test_the_velocity_is_the_difference_of_distinct_captures() -> None:
    velocity = PoseVelocity()
    assert all(math.isnan(v) for v in velocity.update(1.00, (0.0, 0.0, -1.0)))
    assert velocity.update(1.02, (0.004, -0.002, -1.0)) == pytest.approx((0.2, -0.1, 0.0))
    # the same capture again (a mocap frame asked for twice): nothing new to difference
    assert all(math.isnan(v) for v in velocity.update(1.02, (0.004, -0.002, -1.0)))
    assert velocity.update(1.04, (0.008, -0.002, -1.0)) == pytest.approx((0.2, 0.0, 0.0))
    # the mocap lost the vehicle for half a second: no average across the gap, then again
    assert all(math.isnan(v) for v in velocity.update(1.54, (0.108, -0.002, -1.0)))
    assert velocity.update(1.56, (0.112, -0.002, -1.0)) == pytest.approx((0.2, 0.0, 0.0))


def test_captures_arriving_in_bursts_do_not_turn_mocap_noise_into_speed() -> None:
    """A vehicle at rest, mocap noise 0.2 mm, captures every 10 ms but some 1 ms after another
    (a loaded machine): differenced over at least 20 ms the horizontal speed stays under
    0.06 m/s (4 sigma of 0.2 mm * sqrt(2) / 20 ms a axis); between the last two it passes
    0.2 m/s, and PX4 would not arm."""

    def fastest(velocity: PoseVelocity) -> tuple[int, float]:
        rng = np.random.default_rng(3)
        times = np.sort(np.concatenate([np.arange(0.0, 1.0, 0.01), np.arange(0.001, 1.0, 0.05)]))
        speeds = []
        for t in times:
            n = rng.normal(0.0, 0.0002, 3)
            v = velocity.update(float(t), (float(n[0]), float(n[1]), -1.0 + float(n[2])))
            if not math.isnan(v[0]):
                speeds.append(math.hypot(v[0], v[1]))
        return len(speeds), max(speeds)

    count, top = fastest(PoseVelocity())
    assert count > 90 and top < 0.06
    assert fastest(PoseVelocity(min_baseline_s=0.0))[1] > 0.2


@given(ANGLE, ANGLE, st.floats(-3.1, 3.1), SPEED, SPEED, SPEED)
def test_ardupilot_turns_the_body_velocity_back_into_the_ned_one(
    roll: float, pitch: float, yaw: float, vn: float, ve: float, vd: float
) -> None:
    # ArduPilot takes the velocity in BODY_FRD and rotates it with the message's quaternion.
    message = decoded(encode_odometry(MAV, "ardupilot", 1_000_000, (1.0, 2.0, -1.5),
                                      (roll, pitch, yaw), (vn, ve, vd)))  # fmt: skip
    assert rotate(list(message.q), (message.vx, message.vy, message.vz)) == pytest.approx(
        (vn, ve, vd), abs=1e-5
    )
    assert (message.x, message.y, message.z) == pytest.approx((1.0, 2.0, -1.5))


def test_px4_gets_the_ned_velocity_from_a_vision_estimator() -> None:
    message = decoded(encode_odometry(MAV, "px4", 2_000_000, (1.0, 2.0, -1.5), (0.1, 0.2, 1.0),
                                      (0.3, -0.2, 0.1)))  # fmt: skip
    assert (message.vx, message.vy, message.vz) == pytest.approx((0.3, -0.2, 0.1))
    assert message.time_usec == 2_000_000 and message.estimator_type == 2
    assert all(math.isnan(c) for c in message.pose_covariance)  # each takes its noise parameter


@pytest.mark.parametrize("flavor", ["ardupilot", "px4"])
def test_each_autopilot_takes_its_own_frames_and_ardupilot_drops_the_others(flavor: str) -> None:
    own = decoded(encode_odometry(MAV, flavor, 0, (0.0, 0.0, -1.0), (0.0, 0.0, 0.0),
                                  (0.0, 0.0, 0.0)))  # fmt: skip
    fields = (own.frame_id, own.child_frame_id, own.estimator_type, (own.x, own.y, own.z))
    assert odometry_is_pose(flavor, *fields)
    if flavor == "px4":  # PX4's NED frames are not what ArduPilot 4.7 accepts
        assert not odometry_is_pose("ardupilot", *fields)


def test_px4_hands_ekf2_no_mocap_typed_or_positionless_odometry() -> None:
    local_ned, vision, mocap = 1, 2, 6
    assert odometry_is_pose("px4", local_ned, local_ned, vision, (0.0, 0.0, -1.0))
    assert not odometry_is_pose("px4", local_ned, local_ned, mocap, (0.0, 0.0, -1.0))
    assert not odometry_is_pose("px4", local_ned, local_ned, vision, (math.nan, 0.0, -1.0))
