"""Guided setpoint messages -> autopilot targets (pure): NED on the wire, ENU inside.

SET_POSITION_TARGET_LOCAL_NED ``type_mask`` bits (POSITION_TARGET_TYPEMASK) say which fields to
IGNORE: 0-2 position, 3-5 velocity, 6-8 acceleration, 9 force, 10 yaw, 11 yaw rate. ``0x0C00`` is
position + velocity + acceleration; ``0x0DF8`` position only.
"""

from __future__ import annotations

import math
from typing import Any, Protocol

from mavsim.airframe import AttitudeThrust
from mavsim.control import Target
from mavsim.frames import attitude_ned_to_enu, ned_to_enu, quaternion_to_euler

Vec3 = tuple[float, float, float]

IGNORE_POSITION = 0x007
IGNORE_VELOCITY = 0x038
IGNORE_ACCELERATION = 0x1C0
FORCE_SETPOINT = 0x200
IGNORE_YAW = 0x400
FRAME_LOCAL_NED = 1
ATTITUDE_IGNORE_THRUST = 0x40
ATTITUDE_IGNORE_ATTITUDE = 0x80


class HoldsTarget(Protocol):
    """What the conversion needs from the autopilot."""

    target: Target

    def hold_position_m_enu(self) -> Vec3: ...


def position_target_from_message(
    message: Any, autopilot: HoldsTarget, home_m_enu: Vec3
) -> Target | None:
    """A Target in the show frame, or None for a setpoint this autopilot ignores."""
    mask = int(message.type_mask)
    if int(message.coordinate_frame) != FRAME_LOCAL_NED or mask & FORCE_SETPOINT:
        return None
    if mask & IGNORE_POSITION == IGNORE_POSITION:
        position = autopilot.hold_position_m_enu()
    else:
        p = ned_to_enu((message.x, message.y, message.z))
        position = (home_m_enu[0] + p[0], home_m_enu[1] + p[1], home_m_enu[2] + p[2])
    velocity: Vec3 = (0.0, 0.0, 0.0)
    if mask & IGNORE_VELOCITY != IGNORE_VELOCITY:
        velocity = ned_to_enu((message.vx, message.vy, message.vz))
    acceleration: Vec3 = (0.0, 0.0, 0.0)
    if mask & IGNORE_ACCELERATION != IGNORE_ACCELERATION:
        acceleration = ned_to_enu((message.afx, message.afy, message.afz))
    yaw = autopilot.target.yaw_rad
    if not mask & IGNORE_YAW and math.isfinite(message.yaw):
        yaw = math.pi / 2 - float(message.yaw)
    values = (*position, *velocity, *acceleration)
    if not all(math.isfinite(v) for v in values):
        return None
    return Target(position, velocity, acceleration, yaw)


def attitude_target_from_message(message: Any, thrust_max_mps2: float) -> AttitudeThrust | None:
    """Attitude (ENU) and thrust per unit mass; thrust 0..1 is a fraction of the maximum thrust
    (ArduPilot with GUID_OPTIONS bit 3, "SetAttitudeTarget interprets thrust as thrust")."""
    mask = int(message.type_mask)
    if mask & (ATTITUDE_IGNORE_ATTITUDE | ATTITUDE_IGNORE_THRUST):
        return None
    q = tuple(float(v) for v in message.q)
    if len(q) != 4 or not all(math.isfinite(v) for v in q) or not math.isfinite(message.thrust):
        return None
    roll, pitch, yaw = attitude_ned_to_enu(*quaternion_to_euler((q[0], q[1], q[2], q[3])))
    thrust = min(max(float(message.thrust), 0.0), 1.0) * thrust_max_mps2
    return AttitudeThrust(roll, pitch, yaw, thrust)
