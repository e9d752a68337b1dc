"""Guided setpoint messages -> what the autopilot does with them (pure): NED wire, ENU inside.

SET_POSITION_TARGET_LOCAL_NED ``type_mask`` bits (POSITION_TARGET_TYPEMASK) say which fields to
IGNORE: 0-2 position, 3-5 velocity, 6-8 acceleration, 9 "afx..afz are a force", 10 yaw, 11 yaw
rate. Decoded as ArduCopter does (``GCS_MAVLINK_Copter::handle_message_set_position_target_
local_ned``): any bit of a group set ignores the whole vector; then

=======================================  =====================================================
position, velocity (acceleration opt.)   position-velocity-acceleration control
velocity (acceleration optional)         velocity-acceleration control
acceleration only                        acceleration control
position only                            position control (no GUID_TIMEOUT: it holds there)
anything else, a force (bit 9 with       the vehicle stops where it is (``STOP``)
acceleration used), a frame other than
LOCAL_NED/LOCAL_OFFSET_NED/BODY_NED/
BODY_OFFSET_NED, a velocity not finite
=======================================  =====================================================

So ``0x0C00`` is p+v+a, ``0x0800`` p+v+a+yaw, ``0x0DF8`` position only, ``0x09F8`` position and
yaw, ``0x0FF8`` position only (the force bit is harmless while acceleration is ignored) and
``0x0FC7`` velocity only. PX4 accepts the same masks; where ArduCopter stops, PX4 ignores the
message (and says so), see :func:`px4_view`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Literal

from mavsim.frames import attitude_ned_to_enu, ned_to_enu, quaternion_to_euler

Vec3 = tuple[float, float, float]
Control = Literal["pos", "posvelaccel", "velaccel", "accel"]

IGNORE_POSITION = 0x007
IGNORE_VELOCITY = 0x038
IGNORE_ACCELERATION = 0x1C0
FORCE_SETPOINT = 0x200
IGNORE_YAW = 0x400
IGNORE_YAW_RATE = 0x800
FRAME_LOCAL_NED, FRAME_LOCAL_OFFSET_NED, FRAME_BODY_NED, FRAME_BODY_OFFSET_NED = 1, 7, 8, 9
ATTITUDE_IGNORE_BODY_RATES = 0x07
ATTITUDE_IGNORE_THRUST = 0x40
ATTITUDE_IGNORE_ATTITUDE = 0x80


@dataclass(frozen=True)
class GuidedSetpoint:
    """One accepted SET_POSITION_TARGET_LOCAL_NED in the show frame; None: not given."""

    control: Control
    """Which controller takes it (see the module docstring)."""
    position_m_enu: Vec3 | None
    """Target position in [m], ENU (show frame)."""
    velocity_mps_enu: Vec3 | None
    """Target velocity in [m/s], ENU."""
    acceleration_mps2_enu: Vec3 | None
    """Target acceleration in [m/s^2], ENU."""
    yaw_rad: float | None
    """Heading in [rad] about ENU z from east."""
    yaw_rate_radps: float | None
    """Turn rate in [rad/s] about ENU z (counter-clockwise)."""


class Stop:
    """The setpoint is invalid: ArduCopter stops the vehicle where it is."""

    def __init__(self, reason: str) -> None:
        self.reason = reason

    def __repr__(self) -> str:
        return f"Stop({self.reason!r})"


@dataclass(frozen=True)
class Pose:
    """What frame offsets need of the vehicle."""

    home_m_enu: Vec3
    """Origin of LOCAL_NED in the show frame [m]."""
    position_m_enu: Vec3
    """Where the vehicle is [m]."""
    yaw_rad: float
    """Its heading about ENU z from east [rad]."""


def decode_position_target(
    message: Any, pose: Pose, *, any_combination: bool = False
) -> GuidedSetpoint | Stop:
    """ArduCopter's reading of a SET_POSITION_TARGET_LOCAL_NED (see the module docstring);
    ``any_combination``: PX4's, which takes position with acceleration too."""
    frame = int(message.coordinate_frame)
    if frame not in (FRAME_LOCAL_NED, FRAME_LOCAL_OFFSET_NED, FRAME_BODY_NED,
                     FRAME_BODY_OFFSET_NED):  # fmt: skip
        return Stop(f"coordinate frame {frame} unsupported")
    mask = int(message.type_mask)
    use_p, use_v = not mask & IGNORE_POSITION, not mask & IGNORE_VELOCITY
    use_a = not mask & IGNORE_ACCELERATION
    if mask & FORCE_SETPOINT and use_a:
        return Stop("force setpoints are not supported")
    body = frame in (FRAME_BODY_NED, FRAME_BODY_OFFSET_NED)
    velocity = _vector(message.vx, message.vy, message.vz, pose, body) if use_v else None
    if velocity is not None and not all(math.isfinite(v) and abs(v) <= 1000 for v in velocity):
        return Stop("velocity not finite or above 1000 m/s")
    acceleration = _vector(message.afx, message.afy, message.afz, pose, body) if use_a else None
    position = _position(message, pose, frame) if use_p else None
    if use_p and use_v:
        control: Control = "posvelaccel"
    elif use_v:
        control = "velaccel"
    elif use_a and not use_p:
        control = "accel"
    elif use_p and not use_a:
        control = "pos"
    elif use_p and any_combination:
        control = "posvelaccel"
    else:
        return Stop(f"type_mask {mask:#06x} names no supported combination")
    for vector in (position, acceleration):
        if vector is not None and not all(math.isfinite(v) for v in vector):
            return Stop("position or acceleration not finite")
    yaw = None
    if not mask & IGNORE_YAW and math.isfinite(message.yaw):
        yaw = math.pi / 2 - float(message.yaw)
        if body:
            yaw = pose.yaw_rad - float(message.yaw)
    rate = -float(message.yaw_rate) if not mask & IGNORE_YAW_RATE else None
    return GuidedSetpoint(control, position, velocity, acceleration, yaw, rate)


def px4_view(message: Any, pose: Pose) -> GuidedSetpoint | None:
    """PX4's reading: LOCAL_NED and BODY_NED only; where ArduCopter stops, PX4 ignores it."""
    if int(message.coordinate_frame) not in (FRAME_LOCAL_NED, FRAME_BODY_NED):
        return None
    decoded = decode_position_target(message, pose, any_combination=True)
    return None if isinstance(decoded, Stop) else decoded


def _position(message: Any, pose: Pose, frame: int) -> Vec3:
    x, y, z = float(message.x), float(message.y), float(message.z)
    if frame in (FRAME_BODY_NED, FRAME_BODY_OFFSET_NED):
        x, y = _rotate_body(x, y, pose)
    d = ned_to_enu((x, y, z))
    base = pose.home_m_enu if frame == FRAME_LOCAL_NED else pose.position_m_enu
    return (base[0] + d[0], base[1] + d[1], base[2] + d[2])


def _vector(x: float, y: float, z: float, pose: Pose, body: bool) -> Vec3:
    if body:
        x, y = _rotate_body(float(x), float(y), pose)
    return ned_to_enu((float(x), float(y), float(z)))


def _rotate_body(forward: float, right: float, pose: Pose) -> tuple[float, float]:
    """Body forward/right -> north/east at the vehicle's heading."""
    heading_ned = math.pi / 2 - pose.yaw_rad
    c, s = math.cos(heading_ned), math.sin(heading_ned)
    return (c * forward - s * right, s * forward + c * right)


@dataclass(frozen=True)
class AttitudeSetpoint:
    """One accepted SET_ATTITUDE_TARGET: attitude (ENU) and the thrust field, uninterpreted."""

    roll_rad: float
    pitch_rad: float
    yaw_rad: float
    thrust: float
    """The message's thrust field: a thrust fraction or a climb-rate stick (autopilot's call)."""


def decode_attitude_target(message: Any) -> AttitudeSetpoint | Stop:
    """ArduCopter's reading of SET_ATTITUDE_TARGET: thrust must be given, the quaternion unit
    (within 1e-3) unless ignored; body rates are not simulated (a stop if asked for)."""
    mask = int(message.type_mask)
    if mask & ATTITUDE_IGNORE_THRUST:
        return Stop("thrust ignored")
    if mask & ATTITUDE_IGNORE_ATTITUDE or mask & ATTITUDE_IGNORE_BODY_RATES != 0x07:
        return Stop("body-rate targets are not simulated")
    q = tuple(float(v) for v in message.q)
    norm = math.sqrt(sum(v * v for v in q)) if len(q) == 4 else math.nan
    if not abs(norm - 1.0) <= 1e-3 or not math.isfinite(message.thrust):
        return Stop("attitude quaternion not of unit length")
    roll, pitch, yaw = attitude_ned_to_enu(*quaternion_to_euler((q[0], q[1], q[2], q[3])))
    return AttitudeSetpoint(roll, pitch, yaw, float(message.thrust))
