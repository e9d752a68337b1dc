"""The autopilot's own position controller (pure): p/v/a target -> attitude and thrust.

A real autopilot closes the position loop onboard; so does this one. Per axis a PID (with an
integral of the velocity error too, for an autopilot's P-PI cascade) and acceleration
feed-forward (gains in :class:`mavsim.config.PositionGains`) gives an acceleration command; the
thrust vector ``a_cmd + g e_z`` gives the collective thrust and, with the heading, the
roll and pitch commands of the inner loop. Horizontal acceleration is limited so the tilt stays
within ``tilt_max_rad`` (altitude has priority, as in ArduPilot).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mavsim.airframe import AttitudeThrust
from mavsim.config import PositionGains

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Target:
    """Where the autopilot wants the vehicle, world ENU (converted from LOCAL_NED on receipt)."""

    position_m_enu: Vec3
    """Target position in [m]."""
    velocity_mps_enu: Vec3 = (0.0, 0.0, 0.0)
    """Feed-forward velocity in [m/s]."""
    acceleration_mps2_enu: Vec3 = (0.0, 0.0, 0.0)
    """Feed-forward acceleration in [m/s^2]."""
    yaw_rad: float = 0.0
    """Heading in [rad], ENU."""


def thrust_to_attitude(
    accel_mps2_enu: Vec3, yaw_rad: float, gravity_mps2: float, tilt_max_rad: float,
    thrust_max_mps2: float,
) -> AttitudeThrust:  # fmt: skip
    """Roll, pitch and thrust that produce ``accel_mps2_enu`` at heading ``yaw_rad``."""
    fx, fy, fz = accel_mps2_enu[0], accel_mps2_enu[1], accel_mps2_enu[2] + gravity_mps2
    fz = max(fz, 0.1 * gravity_mps2)
    horizontal = math.hypot(fx, fy)
    limit = fz * math.tan(tilt_max_rad)
    if horizontal > limit:
        fx, fy = fx * limit / horizontal, fy * limit / horizontal
    c, s = math.cos(yaw_rad), math.sin(yaw_rad)
    fx_h, fy_h = c * fx + s * fy, -s * fx + c * fy
    thrust = math.sqrt(fx * fx + fy * fy + fz * fz)
    pitch = math.atan2(fx_h, fz)
    roll = math.atan2(-fy_h, math.hypot(fx_h, fz))
    return AttitudeThrust(roll, pitch, yaw_rad, min(thrust, thrust_max_mps2))


class PositionController:
    """PID + feed-forward per axis with an anti-windup integral; :meth:`reset` on mode changes."""

    def __init__(
        self, gains: PositionGains, *, gravity_mps2: float, tilt_max_rad: float,
        thrust_max_mps2: float,
    ) -> None:  # fmt: skip
        self.gains = gains
        self.gravity_mps2 = gravity_mps2
        self.tilt_max_rad = tilt_max_rad
        self.thrust_max_mps2 = thrust_max_mps2
        self._integral = [0.0, 0.0, 0.0]
        self._velocity_integral = [0.0, 0.0, 0.0]

    def reset(self) -> None:
        """Forget the error integrals."""
        self._integral = [0.0, 0.0, 0.0]
        self._velocity_integral = [0.0, 0.0, 0.0]

    def acceleration(
        self, target: Target, position_m_enu: Vec3, velocity_mps_enu: Vec3, dt_s: float
    ) -> Vec3:
        """Commanded acceleration in [m/s^2], ENU; integrates the error over ``dt_s``."""
        g = self.gains
        out = []
        limit = g.integral_limit_m_s
        for axis in range(3):
            z = axis == 2
            kp, kd = (g.kp_z, g.kd_z) if z else (g.kp_xy, g.kd_xy)
            ki, kvi = (g.ki_z, g.kvi_z) if z else (g.ki_xy, g.kvi_xy)
            error = target.position_m_enu[axis] - position_m_enu[axis]
            error_v = target.velocity_mps_enu[axis] - velocity_mps_enu[axis]
            self._integral[axis] = min(max(self._integral[axis] + error * dt_s, -limit), limit)
            summed = self._velocity_integral[axis] + error_v * dt_s
            self._velocity_integral[axis] = min(max(summed, -limit), limit)
            out.append(
                target.acceleration_mps2_enu[axis] + kp * error + kd * error_v
                + ki * self._integral[axis] + kvi * self._velocity_integral[axis]
            )  # fmt: skip
        return (out[0], out[1], out[2])

    def update(
        self, target: Target, position_m_enu: Vec3, velocity_mps_enu: Vec3, dt_s: float
    ) -> AttitudeThrust:
        """Inner-loop command for one period."""
        accel = self.acceleration(target, position_m_enu, velocity_mps_enu, dt_s)
        return thrust_to_attitude(
            accel, target.yaw_rad, self.gravity_mps2, self.tilt_max_rad, self.thrust_max_mps2
        )
