"""GUIDED (PX4: OFFBOARD) control of the simulated autopilot, in pure functions.

- a position setpoint replaces the fields it gives; the others continue from the current target
  (velocity control keeps integrating its position, acceleration control its velocity);
- between setpoints the target moves on with its velocity and acceleration, as ArduPilot's position
  controller does, so 50 Hz setpoints drive a 100+ Hz loop smoothly;
- GUID_TIMEOUT: position-only targets never time out (they are where to stay); with velocity or
  acceleration, after the timeout both are zeroed and the vehicle stops; attitude targets level
  the vehicle at its heading and hold the height;
- yaw: an angle or a rate when the setpoint gives one; otherwise WP_YAW_BEHAVIOR 0 holds the
  heading, any other value turns the vehicle to face its direction of travel;
- attitude thrust: with GUID_OPTIONS bit 3 a fraction of the maximum thrust, otherwise ArduCopter's
  climb-rate stick, 0.5 for no climb, 1 for WPNAV_SPEED_UP, 0 for WPNAV_SPEED_DN down.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace
from typing import Literal

from mavsim.airframe import AttitudeThrust
from mavsim.control import Target
from mavsim.wire import AttitudeSetpoint, Control, GuidedSetpoint

Vec3 = tuple[float, float, float]
YawMode = Literal["hold", "angle", "rate", "auto"]
AUTO_YAW_MIN_SPEED_MPS = 0.1
"""Slower than this the vehicle does not turn to face its direction of travel."""
GUID_OPTIONS_THRUST_AS_THRUST = 8


@dataclass(frozen=True)
class Heading:
    """How the yaw target evolves."""

    mode: YawMode = "hold"
    rate_radps: float = 0.0
    """Turn rate about ENU z with mode ``rate``."""


def merge(sp: GuidedSetpoint, current: Target, hold_m_enu: Vec3) -> Target:
    """The new target: the setpoint's fields, the others continued (see the module docstring)."""
    zero = (0.0, 0.0, 0.0)
    position = sp.position_m_enu if sp.position_m_enu is not None else hold_m_enu
    if sp.control == "accel":
        velocity = current.velocity_mps_enu
    else:
        velocity = sp.velocity_mps_enu if sp.velocity_mps_enu is not None else zero
    acceleration = sp.acceleration_mps2_enu if sp.acceleration_mps2_enu is not None else zero
    yaw = sp.yaw_rad if sp.yaw_rad is not None else current.yaw_rad
    return Target(position, velocity, acceleration, yaw)


def heading_of(sp: GuidedSetpoint, wp_yaw_behavior: float) -> Heading:
    """How the yaw target evolves after this setpoint."""
    if sp.yaw_rad is not None:
        return Heading("angle")
    if sp.yaw_rate_radps is not None:
        return Heading("rate", sp.yaw_rate_radps)
    return Heading("hold" if wp_yaw_behavior == 0 else "auto")


def propagate(target: Target, heading: Heading, vehicle_m_enu: Vec3, dt_s: float) -> Target:
    """The target one period later: moved on with its velocity and acceleration; yaw turned."""
    p, v, a = target.position_m_enu, target.velocity_mps_enu, target.acceleration_mps2_enu
    moving = v != (0.0, 0.0, 0.0) or a != (0.0, 0.0, 0.0)
    if moving:
        p = _vec(p[i] + v[i] * dt_s + 0.5 * a[i] * dt_s * dt_s for i in range(3))
        v = _vec(v[i] + a[i] * dt_s for i in range(3))
    yaw = target.yaw_rad
    if heading.mode == "rate":
        yaw = _wrap(yaw + heading.rate_radps * dt_s)
    elif heading.mode == "auto":
        dx, dy = v[0], v[1]
        if math.hypot(dx, dy) < AUTO_YAW_MIN_SPEED_MPS:
            dx, dy = p[0] - vehicle_m_enu[0], p[1] - vehicle_m_enu[1]
        if math.hypot(dx, dy) >= AUTO_YAW_MIN_SPEED_MPS:
            yaw = math.atan2(dy, dx)
    if not moving and yaw == target.yaw_rad:
        return target
    return Target(p, v, a, yaw)


def timed_out(control: Control | Literal["attitude"], target: Target) -> Target:
    """GUID_TIMEOUT on a position target: velocity and acceleration zeroed (the position where
    the target had got to stays); position-only targets are unchanged."""
    if control == "pos":
        return target
    return replace(target, velocity_mps_enu=(0.0, 0.0, 0.0), acceleration_mps2_enu=(0.0, 0.0, 0.0))


@dataclass(frozen=True)
class AttitudeHold:
    """An attitude target as the autopilot flies it."""

    setpoint: AttitudeSetpoint
    """Attitude (ENU) and the thrust field."""
    use_thrust: bool
    """The thrust field is thrust (GUID_OPTIONS bit 3, PX4); otherwise a climb-rate stick."""
    climb_z_m: float
    """Height target in [m] the climb-rate stick moves."""


def climb_rate_mps(thrust: float, speed_up_cmps: float, speed_down_cmps: float) -> float:
    """ArduCopter's thrust-as-climb-rate: 0.5 holds, 1 climbs at WPNAV_SPEED_UP, 0 descends at
    WPNAV_SPEED_DN (both in [cm/s])."""
    t = min(max(thrust, 0.0), 1.0)
    if t >= 0.5:
        return (t - 0.5) * 2.0 * speed_up_cmps / 100.0
    return -(0.5 - t) * 2.0 * speed_down_cmps / 100.0


def attitude_command(
    hold: AttitudeHold,
    *,
    z_m: float,
    vz_mps: float,
    thrust_max_mps2: float,
    gravity_mps2: float,
    kp_z: float,
    kd_z: float,
    climb_mps: float,
) -> AttitudeThrust:
    """The inner-loop command of an attitude target; with the climb-rate stick the height loop
    (``kp_z``, ``kd_z``) gives the thrust."""
    sp = hold.setpoint
    if hold.use_thrust:
        thrust = min(max(sp.thrust, 0.0), 1.0) * thrust_max_mps2
    else:
        tilt = max(math.cos(sp.roll_rad) * math.cos(sp.pitch_rad), 0.5)
        accel = kp_z * (hold.climb_z_m - z_m) + kd_z * (climb_mps - vz_mps)
        thrust = min(max((gravity_mps2 + accel) / tilt, 0.0), thrust_max_mps2)
    return AttitudeThrust(sp.roll_rad, sp.pitch_rad, sp.yaw_rad, thrust)


def _vec(values: Iterable[float]) -> Vec3:
    x, y, z = values
    return (float(x), float(y), float(z))


def _wrap(angle: float) -> float:
    return (angle + math.pi) % (2 * math.pi) - math.pi
