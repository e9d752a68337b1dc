"""Straight, rest-to-rest moves between hover points (pure): take-off transit, brush lift, return.

A move follows the minimum-jerk quintic ``s(u) = 10u^3 - 15u^4 + 6u^5`` along the straight line
from ``start`` to ``end``. Its peak speed is ``15/8 * d / T`` and its peak acceleration
``10 / sqrt(3) * d / T^2`` (at ``u = 1/2 -+ sqrt(3)/6``), so the duration that respects a speed
limit ``v`` and an acceleration limit ``a`` is ``T = max(15 d / (8 v), sqrt(10 d / (sqrt(3) a)))``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from vehicle_agent.backends.base import Setpoint, Vec3

PEAK_SPEED_FACTOR = 15.0 / 8.0
"""Peak speed of the quintic in units of distance / duration."""
PEAK_ACCEL_FACTOR = 10.0 / math.sqrt(3.0)
"""Peak acceleration of the quintic in units of distance / duration^2."""


@dataclass(frozen=True)
class Move:
    """A rest-to-rest straight move that starts at ``t0_s``."""

    start_m_enu: Vec3
    """Where the move starts in [m], ENU."""
    end_m_enu: Vec3
    """Where it ends in [m], ENU."""
    t0_s: float
    """Agent time in [s] when it starts."""
    duration_s: float
    """Length in [s]; 0 for a move of zero length."""

    @property
    def end_s(self) -> float:
        """Agent time in [s] when the move is over."""
        return self.t0_s + self.duration_s

    def done(self, now_s: float) -> bool:
        """True once ``now_s`` is at or after the end."""
        return now_s >= self.end_s

    def setpoint(self, now_s: float) -> Setpoint:
        """Reference position, velocity and acceleration at agent time ``now_s`` (clamped)."""
        if self.duration_s <= 0.0:
            return Setpoint(position_m_enu=self.end_m_enu)
        big_t = self.duration_s
        u = min(max((now_s - self.t0_s) / big_t, 0.0), 1.0)
        s = u**3 * (10.0 - 15.0 * u + 6.0 * u * u)
        ds = 30.0 * u * u * (1.0 - u) ** 2 / big_t
        dds = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u) / (big_t * big_t)
        delta = tuple(e - a for a, e in zip(self.start_m_enu, self.end_m_enu, strict=True))
        pos = tuple(a + s * d for a, d in zip(self.start_m_enu, delta, strict=True))
        vel = tuple(ds * d for d in delta)
        acc = tuple(dds * d for d in delta)
        return Setpoint(
            position_m_enu=_vec(pos), velocity_mps_enu=_vec(vel), acceleration_mps2_enu=_vec(acc)
        )


def _vec(values: tuple[float, ...]) -> Vec3:
    return (float(values[0]), float(values[1]), float(values[2]))


def move_duration_s(distance_m: float, v_max_mps: float, a_max_mps2: float) -> float:
    """Shortest quintic duration in [s] over ``distance_m`` within speed and acceleration limits."""
    if distance_m <= 0.0:
        return 0.0
    return max(
        PEAK_SPEED_FACTOR * distance_m / v_max_mps,
        math.sqrt(PEAK_ACCEL_FACTOR * distance_m / a_max_mps2),
    )


def plan_move(
    start_m_enu: Vec3, end_m_enu: Vec3, t0_s: float, *, v_max_mps: float, a_max_mps2: float
) -> Move:
    """The quickest rest-to-rest move from ``start`` to ``end`` within the limits."""
    distance = math.dist(start_m_enu, end_m_enu)
    return Move(start_m_enu, end_m_enu, t0_s, move_duration_s(distance, v_max_mps, a_max_mps2))
