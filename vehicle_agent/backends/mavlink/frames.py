"""ENU <-> NED at the MAVLink boundary, and nowhere else (pure).

Inside skyquill the world frame is ENU (x east, y north, z up) with bodies forward-left-up (FLU);
MAVLink's LOCAL_NED is x north, y east, z down with bodies forward-right-down (FRD), and its origin
is wherever the autopilot's estimator started (its home). :class:`LocalFrame` holds that origin in
the show frame, so ``show = origin + R (local_ned)``.

Attitudes are Z-Y-X Euler angles (roll, pitch, yaw) in [rad]; MAVLink quaternions are (w, x, y, z).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

Vec3 = tuple[float, float, float]
Quaternion = tuple[float, float, float, float]
Mat3 = tuple[Vec3, Vec3, Vec3]


def enu_to_ned(v: Vec3) -> Vec3:
    """A vector given in ENU, expressed in NED (the map is its own inverse)."""
    return (v[1], v[0], -v[2])


def ned_to_enu(v: Vec3) -> Vec3:
    """A vector given in NED, expressed in ENU."""
    return (v[1], v[0], -v[2])


def yaw_enu_to_ned(yaw_rad: float) -> float:
    """Heading from east counter-clockwise -> heading from north clockwise, in [-pi, pi)."""
    return _wrap(math.pi / 2 - yaw_rad)


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi


@dataclass(frozen=True)
class LocalFrame:
    """One vehicle's LOCAL_NED frame placed in the show frame."""

    origin_m_enu: Vec3
    """Where the vehicle's LOCAL_NED origin is in the show frame, in [m] ENU."""

    def position_to_ned(self, p_m_enu: Vec3) -> Vec3:
        """Show-frame position -> LOCAL_NED position in [m]."""
        o = self.origin_m_enu
        return enu_to_ned((p_m_enu[0] - o[0], p_m_enu[1] - o[1], p_m_enu[2] - o[2]))

    def position_from_ned(self, p_m_ned: Vec3) -> Vec3:
        """LOCAL_NED position -> show-frame position in [m]."""
        d = ned_to_enu(p_m_ned)
        o = self.origin_m_enu
        return (o[0] + d[0], o[1] + d[1], o[2] + d[2])


def euler_to_matrix(roll: float, pitch: float, yaw: float) -> Mat3:
    """Rotation body -> world of Z-Y-X Euler angles."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return (
        (cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr),
        (sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr),
        (-sp, cp * sr, cp * cr),
    )


def matrix_to_euler(r: Mat3) -> Vec3:
    """Z-Y-X Euler angles (roll, pitch, yaw) of a rotation body -> world."""
    roll = math.atan2(r[2][1], r[2][2])
    pitch = -math.asin(max(-1.0, min(1.0, r[2][0])))
    yaw = math.atan2(r[1][0], r[0][0])
    return (roll, pitch, yaw)


def _convert(r: Mat3) -> Mat3:
    """``T r S``: T swaps world ENU <-> NED, S flips body FLU <-> FRD (both self-inverse)."""
    rows = (r[1], r[0], (-r[2][0], -r[2][1], -r[2][2]))
    a, b, c = ((row[0], -row[1], -row[2]) for row in rows)
    return (a, b, c)


def attitude_enu_to_ned(roll: float, pitch: float, yaw: float) -> Vec3:
    """Euler angles of an FLU body in ENU -> the same attitude of the FRD body in NED."""
    return matrix_to_euler(_convert(euler_to_matrix(roll, pitch, yaw)))


def attitude_ned_to_enu(roll: float, pitch: float, yaw: float) -> Vec3:
    """Euler angles of an FRD body in NED -> the same attitude of the FLU body in ENU."""
    return matrix_to_euler(_convert(euler_to_matrix(roll, pitch, yaw)))


def euler_to_quaternion(roll: float, pitch: float, yaw: float) -> Quaternion:
    """Z-Y-X Euler angles -> unit quaternion (w, x, y, z)."""
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (
        cr * cp * cy + sr * sp * sy,
        sr * cp * cy - cr * sp * sy,
        cr * sp * cy + sr * cp * sy,
        cr * cp * sy - sr * sp * cy,
    )


def attitude_ned_to_xyzw_enu(roll: float, pitch: float, yaw: float) -> Quaternion:
    """Euler angles of an FRD body in NED (MAVLink's ATTITUDE) -> the quaternion (x, y, z, w)
    of the same attitude of the FLU body in ENU (``Telemetry.attitude_xyzw_enu``)."""
    w, x, y, z = euler_to_quaternion(*attitude_ned_to_enu(roll, pitch, yaw))
    return (x, y, z, w) if w >= 0 else (-x, -y, -z, -w)


def quaternion_to_euler(q: Quaternion) -> Vec3:
    """Quaternion (w, x, y, z) -> Z-Y-X Euler angles (roll, pitch, yaw)."""
    w, x, y, z = q
    n = math.sqrt(w * w + x * x + y * y + z * z) or 1.0
    w, x, y, z = w / n, x / n, y / n, z / n
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return (roll, pitch, yaw)
