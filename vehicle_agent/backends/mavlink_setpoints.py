"""What a setpoint becomes on the wire (pure): LOCAL_NED p/v/a, or attitude + thrust.

Position setpoints carry position, velocity, acceleration and yaw (type_mask ``0x0800``: ignore only
the yaw rate): ArduPilot and PX4 use p, v, a as feed-forward (measured on ArduCopter SITL this
tracks a trajectory far better than position-only targets, ``0x0DF8``), and the explicit yaw keeps
the autopilot from turning the vehicle (the heading at take-off is held). Attitude setpoints come
from our own RPT outer loop (:mod:`vehicles.quadrotor_brush.control.controller`) closed on the
autopilot's LOCAL_POSITION_NED, at the held heading, with thrust as a fraction of the maximum thrust
(ArduPilot: GUID_OPTIONS bit 3, set at connect; PX4: normalised thrust).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from vehicle_agent.backends.base import Setpoint, Vec3
from vehicle_agent.backends.mavlink_frames import (
    LocalFrame,
    Quaternion,
    attitude_enu_to_ned,
    enu_to_ned,
    euler_to_quaternion,
)
from vehicles.quadrotor_brush.control.controller import (
    ControllerConfig,
    PositionController,
    ReferenceTick,
)
from vehicles.quadrotor_brush.control.inner import G_C

TYPE_MASK_POSITION_VELOCITY_ACCEL = 0x0C00
"""POSITION_TARGET_TYPEMASK: use x, y, z, vx, vy, vz, afx, afy, afz; ignore yaw and yaw rate."""
TYPE_MASK_POSITION_VELOCITY_ACCEL_YAW = 0x0800
"""POSITION_TARGET_TYPEMASK: use x, y, z, vx, vy, vz, afx, afy, afz and yaw; ignore yaw rate."""
TYPE_MASK_ATTITUDE_ONLY = 0x07
"""ATTITUDE_TARGET_TYPEMASK: ignore the three body rates, use the quaternion and thrust."""
MAV_FRAME_LOCAL_NED = 1


@dataclass(frozen=True)
class NedTarget:
    """A setpoint in the vehicle's LOCAL_NED frame."""

    position_m_ned: Vec3
    """Position in [m] relative to the vehicle's LOCAL_NED origin."""
    velocity_mps_ned: Vec3
    """Velocity in [m/s]."""
    acceleration_mps2_ned: Vec3
    """Acceleration in [m/s^2]."""


def ned_target(setpoint: Setpoint, frame: LocalFrame) -> NedTarget:
    """The setpoint in the vehicle's LOCAL_NED frame."""
    return NedTarget(
        frame.position_to_ned(setpoint.position_m_enu),
        enu_to_ned(setpoint.velocity_mps_enu),
        enu_to_ned(setpoint.acceleration_mps2_enu),
    )


@dataclass(frozen=True)
class AttitudeCommand:
    """One SET_ATTITUDE_TARGET."""

    q_ned: Quaternion
    """Attitude of the FRD body in NED as (w, x, y, z)."""
    thrust: float
    """Collective thrust as a fraction 0..1 of the maximum."""


class AttitudeOuterLoop:
    """Our RPT position controller for one vehicle, fed with the autopilot's position."""

    def __init__(
        self,
        config: ControllerConfig,
        dt_s: float,
        initial_position_m_enu: Vec3,
        thrust_max_mps2: float,
        *,
        heading_ned_rad: float = 0.0,
    ) -> None:
        self._controller = PositionController(config, dt_s, np.array([initial_position_m_enu]))
        self._thrust_max_mps2 = thrust_max_mps2
        self._yaw_enu = np.array([math.pi / 2 - heading_ned_rad])
        """The heading to hold, about ENU z from east."""
        self._throttle_per_mps2 = float(G_C[0, 2])

    def update(self, measured_m_enu: Vec3, setpoint: Setpoint) -> AttitudeCommand:
        """One control period: the attitude and thrust that track ``setpoint``."""
        tick = ReferenceTick(
            position_m_enu=np.array([setpoint.position_m_enu]),
            velocity_mps_enu=np.array([setpoint.velocity_mps_enu]),
            acceleration_mps2_enu=np.array([setpoint.acceleration_mps2_enu]),
            yaw_rad=self._yaw_enu,
        )
        out = self._controller.update(np.array([measured_m_enu]), tick)
        roll, pitch, yaw = (float(out.roll_rad[0]), float(out.pitch_rad[0]), float(out.yaw_rad[0]))
        thrust_mps2 = float(out.throttle[0]) / self._throttle_per_mps2
        fraction = min(max(thrust_mps2 / self._thrust_max_mps2, 0.0), 1.0)
        return AttitudeCommand(
            euler_to_quaternion(*attitude_enu_to_ned(roll, pitch, yaw)), fraction
        )
