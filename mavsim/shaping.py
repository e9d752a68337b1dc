"""ArduCopter's input shaping of guided targets (pure): what its position controller flies.

ArduCopter does not hand a new guided position straight to its position loop. Each loop it moves
a *desired* state (position, velocity, acceleration) towards the target along a jerk-limited path
(AC_PosControl ``input_pos_vel_accel``; AP_Math ``shape_pos_vel_accel``), and the loop follows
that state with its velocity and acceleration as feed-forward. The shape, per loop of ``dt``:

- the desired state moves on by its own velocity and acceleration;
- a velocity to close the position gap: linear (gain ``jerk / (2 accel)``) near the target, a
  square root (braking at ``accel / 2``) further out, capped at the speed limit, plus the
  target's own velocity;
- an acceleration to reach that velocity: the same law one order up (gain ``jerk / accel``,
  square root with ``jerk``), capped at ``accel``, plus the target's own acceleration;
- the desired acceleration moves towards that at no more than ``jerk``.

Horizontal axes are shaped as one vector (WPNAV_SPEED, WPNAV_ACCEL, PSC_JERK_XY), the vertical
axis on its own (WPNAV_SPEED_UP / WPNAV_SPEED_DN, WPNAV_ACCEL_Z, PSC_JERK_Z). A 1 m step then
takes about 1.2 s to half way with a few per cent overshoot, as ArduCopter SITL does, where a bare
position loop would jump.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from mavsim.control import Target
from mavsim.params import ParamTable

Vec3 = tuple[float, float, float]
Vec2 = tuple[float, float]
ZERO: Vec3 = (0.0, 0.0, 0.0)
VERTICAL_ACCEL_CAP_MPS2 = 7.5
"""ArduCopter never shapes a descent harder than this, in [m/s^2]."""


@dataclass(frozen=True)
class ShapeLimits:
    """The limits of the shaped path, SI units (ArduCopter keeps them in cm)."""

    speed_xy_mps: float
    """Horizontal speed limit in [m/s] (WPNAV_SPEED / 100)."""
    speed_up_mps: float
    """Climb rate limit in [m/s] (WPNAV_SPEED_UP / 100)."""
    speed_down_mps: float
    """Descent rate limit in [m/s], positive (WPNAV_SPEED_DN / 100)."""
    accel_xy_mps2: float
    """Horizontal acceleration limit in [m/s^2] (WPNAV_ACCEL / 100)."""
    accel_z_mps2: float
    """Vertical acceleration limit in [m/s^2] (WPNAV_ACCEL_Z / 100)."""
    jerk_xy_mps3: float
    """Horizontal jerk limit in [m/s^3] (PSC_JERK_XY)."""
    jerk_z_mps3: float
    """Vertical jerk limit in [m/s^3] (PSC_JERK_Z)."""


def shape_limits(params: ParamTable) -> ShapeLimits:
    """The limits ArduCopter's parameters set, each floored at 1 % of its default (a zero would
    stop the path)."""

    def value(name: str, scale: float) -> float:
        return max(params[name], 0.01 * params.defs[name].default) * scale

    return ShapeLimits(
        speed_xy_mps=value("WPNAV_SPEED", 0.01), speed_up_mps=value("WPNAV_SPEED_UP", 0.01),
        speed_down_mps=value("WPNAV_SPEED_DN", 0.01), accel_xy_mps2=value("WPNAV_ACCEL", 0.01),
        accel_z_mps2=value("WPNAV_ACCEL_Z", 0.01), jerk_xy_mps3=value("PSC_JERK_XY", 1.0),
        jerk_z_mps3=value("PSC_JERK_Z", 1.0),
    )  # fmt: skip


def sqrt_rate(error: float, gain: float, limit: float, dt_s: float) -> float:
    """The rate that closes ``error``: ``gain * error`` near zero, ``sqrt(2 limit |e|)``-shaped
    beyond ``limit / gain^2`` (so the next order stays within ``limit``), never more than closes
    the error within one ``dt_s``."""
    linear = limit / (gain * gain)
    size = abs(error)
    rate = gain * size if size <= linear else math.sqrt(2.0 * limit * (size - linear / 2.0))
    rate = min(rate, size / dt_s)
    return math.copysign(rate, error)


def _scaled(v: Vec2, length: float) -> Vec2:
    size = math.hypot(*v)
    if size <= length or size == 0.0:
        return v
    return (v[0] * length / size, v[1] * length / size)


def _sqrt_rate_xy(error: Vec2, gain: float, limit: float, dt_s: float) -> Vec2:
    size = math.hypot(*error)
    if size == 0.0:
        return (0.0, 0.0)
    rate = sqrt_rate(size, gain, limit, dt_s)
    return (error[0] * rate / size, error[1] * rate / size)


def _shape_xy(target: Target, p: Vec2, v: Vec2, a: Vec2, limits: ShapeLimits, dt_s: float) -> Vec2:
    """The new horizontal desired acceleration."""
    accel, jerk = limits.accel_xy_mps2, limits.jerk_xy_mps3
    tp, tv, ta = target.position_m_enu, target.velocity_mps_enu, target.acceleration_mps2_enu
    gap = (tp[0] - p[0], tp[1] - p[1])
    closing = _scaled(
        _sqrt_rate_xy(gap, 0.5 * jerk / accel, 0.5 * accel, dt_s), limits.speed_xy_mps
    )
    want_v = (closing[0] + tv[0], closing[1] + tv[1])
    correction = _sqrt_rate_xy((want_v[0] - v[0], want_v[1] - v[1]), jerk / accel, jerk, dt_s)
    correction = _scaled(correction, accel)
    want_a = (correction[0] + ta[0], correction[1] + ta[1])
    step = _scaled((want_a[0] - a[0], want_a[1] - a[1]), jerk * dt_s)
    return (a[0] + step[0], a[1] + step[1])


def _shape_z(
    target: Target, p: float, v: float, a: float, limits: ShapeLimits, dt_s: float
) -> float:
    """The new vertical desired acceleration (ENU: up is positive)."""
    up, down = limits.accel_z_mps2, min(limits.accel_z_mps2, VERTICAL_ACCEL_CAP_MPS2)
    jerk = limits.jerk_z_mps3
    gap = target.position_m_enu[2] - p
    brake = down if gap > 0.0 else up  # closing a gap upwards ends braking downwards
    closing = sqrt_rate(gap, 0.5 * jerk / brake, 0.5 * brake, dt_s)
    closing = min(max(closing, -limits.speed_down_mps), limits.speed_up_mps)
    error_v = closing + target.velocity_mps_enu[2] - v
    push = up if error_v > 0.0 else down
    correction = min(max(sqrt_rate(error_v, jerk / push, jerk, dt_s), -down), up)
    want_a = correction + target.acceleration_mps2_enu[2]
    return a + min(max(want_a - a, -jerk * dt_s), jerk * dt_s)


class TargetShaper:
    """The desired state ArduCopter's position loop follows towards a guided target."""

    def __init__(self) -> None:
        self.desired: Target | None = None
        """The shaped state (None: start from the vehicle's state at the next step)."""

    def reset(self) -> None:
        """Start again from the vehicle's state (mode changes, take-off, a stop)."""
        self.desired = None

    def step(
        self, target: Target, position_m_enu: Vec3, velocity_mps_enu: Vec3, limits: ShapeLimits,
        dt_s: float,
    ) -> Target:  # fmt: skip
        """One loop of ``dt_s`` towards ``target``; the desired state for the position loop."""
        d = self.desired or Target(position_m_enu, velocity_mps_enu, ZERO, target.yaw_rad)
        p0, v0, a0 = d.position_m_enu, d.velocity_mps_enu, d.acceleration_mps2_enu
        p = tuple(p0[i] + v0[i] * dt_s + 0.5 * a0[i] * dt_s * dt_s for i in range(3))
        v = tuple(v0[i] + a0[i] * dt_s for i in range(3))
        axy = _shape_xy(target, (p[0], p[1]), (v[0], v[1]), (a0[0], a0[1]), limits, dt_s)
        az = _shape_z(target, p[2], v[2], a0[2], limits, dt_s)
        self.desired = Target((p[0], p[1], p[2]), (v[0], v[1], v[2]), (axy[0], axy[1], az),
                              target.yaw_rad)  # fmt: skip
        return self.desired
