"""Frames of a simulated autopilot: the show frame is ENU/FLU, MAVLink speaks NED/FRD.

The vehicle's LOCAL_NED origin is its home (where it started), as on a real ArduCopter.
Attitudes are Z-Y-X Euler angles (yaw, pitch, roll) of the body frame in the world frame.
"""

from __future__ import annotations

import math

Vec3 = tuple[float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]


def enu_to_ned(v: Vec3) -> Vec3:
    """A vector in ENU expressed in NED (the same map both ways)."""
    return (v[1], v[0], -v[2])


ned_to_enu = enu_to_ned


def euler_to_matrix(roll: float, pitch: float, yaw: float) -> Mat3:
    """Rotation body -> world of Z-Y-X Euler angles in [rad]."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def matrix_to_euler(r: Mat3) -> Vec3:
    """Z-Y-X Euler angles (roll, pitch, yaw) in [rad] of a rotation body -> world."""
    roll = math.atan2(r[2][1], r[2][2])
    pitch = -math.asin(max(-1.0, min(1.0, r[2][0])))
    yaw = math.atan2(r[1][0], r[0][0])
    return (roll, pitch, yaw)


def _swap_world_and_flip_body(r: Mat3) -> Mat3:
    """``T r S`` with T = ENU<->NED (swap x, y; negate z) and S = FLU<->FRD (negate y, z)."""
    rows = (r[1], r[0], (-r[2][0], -r[2][1], -r[2][2]))
    return tuple((row[0], -row[1], -row[2]) for row in rows)  # type: ignore[return-value]


def attitude_enu_to_ned(roll: float, pitch: float, yaw: float) -> Vec3:
    """Euler angles of a body FLU in ENU -> the same attitude as body FRD in NED."""
    return matrix_to_euler(_swap_world_and_flip_body(euler_to_matrix(roll, pitch, yaw)))


def attitude_ned_to_enu(roll: float, pitch: float, yaw: float) -> Vec3:
    """Euler angles of a body FRD in NED -> the same attitude as body FLU in ENU."""
    return matrix_to_euler(_swap_world_and_flip_body(euler_to_matrix(roll, pitch, yaw)))


def quaternion_to_euler(q: tuple[float, float, float, float]) -> Vec3:
    """MAVLink quaternion (w, x, y, z) -> Z-Y-X Euler angles (roll, pitch, yaw) in [rad]."""
    w, x, y, z = q
    norm = math.sqrt(w * w + x * x + y * y + z * z) or 1.0
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return (roll, pitch, yaw)
