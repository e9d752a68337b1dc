"""What a setpoint becomes on the wire (pure): LOCAL_NED p/v/a and the held yaw.

Position setpoints carry position, velocity, acceleration and yaw (type_mask ``0x0800``: ignore only
the yaw rate): ArduPilot and PX4 use p, v, a as feed-forward (measured on ArduCopter SITL this
tracks a trajectory far better than position-only targets, ``0x0DF8``), and the explicit yaw keeps
the autopilot from turning the vehicle (the heading at take-off is held).

There are no attitude setpoints: our outer loop over SET_ATTITUDE_TARGET diverged on ArduCopter
SITL (pitch swinging to 27 degrees, a deviation abort at 0.69 m in the first transit) and left
mavsim's shaped autopilots beyond the 0.15 m bound, so it was removed (issue 11).
"""

from __future__ import annotations

from dataclasses import dataclass

from vehicle_agent.backends.base import Setpoint, Vec3
from vehicle_agent.backends.mavlink.frames import LocalFrame, enu_to_ned

TYPE_MASK_POSITION_VELOCITY_ACCEL = 0x0C00
"""POSITION_TARGET_TYPEMASK: use x, y, z, vx, vy, vz, afx, afy, afz; ignore yaw and yaw rate."""
TYPE_MASK_POSITION_VELOCITY_ACCEL_YAW = 0x0800
"""POSITION_TARGET_TYPEMASK: use x, y, z, vx, vy, vz, afx, afy, afz and yaw; ignore yaw rate."""
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
