"""The autopilot's own motions, as targets moved one period at a time (pure): LAND descent,
RTL's return at height."""

from __future__ import annotations

import math
from dataclasses import replace

from mavsim.control import Target

Vec3 = tuple[float, float, float]
ZERO: Vec3 = (0.0, 0.0, 0.0)


def descend(target: Target, speed_mps: float, ground_z_m: float, dt_s: float) -> Target:
    """LAND: the target sinks at ``speed_mps`` until below the ground (touch-down ends it)."""
    x, y, z = target.position_m_enu
    z_next = max(z - speed_mps * dt_s, ground_z_m - 0.3)
    return replace(target, position_m_enu=(x, y, z_next), velocity_mps_enu=(0.0, 0.0, -speed_mps),
                   acceleration_mps2_enu=ZERO)  # fmt: skip


def go_home(target: Target, home_m_enu: Vec3, speed_mps: float, dt_s: float) -> Target:
    """RTL: the target moves at its height towards above home at ``speed_mps``."""
    x, y, z = target.position_m_enu
    dx, dy = home_m_enu[0] - x, home_m_enu[1] - y
    distance = math.hypot(dx, dy)
    step = speed_mps * dt_s
    if distance <= step:
        return Target(position_m_enu=(home_m_enu[0], home_m_enu[1], z), yaw_rad=target.yaw_rad)
    position = (x + dx * step / distance, y + dy * step / distance, z)
    return replace(target, position_m_enu=position, velocity_mps_enu=ZERO,
                   acceleration_mps2_enu=ZERO)  # fmt: skip
