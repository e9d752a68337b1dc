"""Synthetic writing references (plain arrays) for tests and benchmarks.

A reference hovers above the start, descends to writing height, writes one closed figure (circle or
figure eight) with a minimum-jerk progress along the path, climbs back and hovers. Positions,
velocities and accelerations are exact derivatives, not finite differences.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sim.errors import SimError

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class ReferenceArrays:
    """A sampled reference, world ENU, SI units (the shape of ``planner.samples``)."""

    t_s: FloatArray
    """Sample times in [s], shape (K,), from 0."""
    position_m_enu: FloatArray
    """Reference position in [m], shape (K, 3)."""
    velocity_mps_enu: FloatArray
    """Reference velocity in [m/s], shape (K, 3)."""
    acceleration_mps2_enu: FloatArray
    """Reference acceleration in [m/s^2], shape (K, 3)."""
    pen_down: BoolArray
    """Whether the reference is writing, shape (K,)."""


def _min_jerk(tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 and its first two derivatives in tau."""
    s = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    ds = 30.0 * tau**2 * (1.0 - tau) ** 2
    dds = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau)
    return s, ds, dds


def _shape(name: str, s: FloatArray, size_m: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Point, first and second derivative in s of a closed figure starting at the origin."""
    w = 2.0 * math.pi
    half = 0.5 * size_m
    if name == "circle":
        p = half * np.stack((np.cos(w * s) - 1.0, np.sin(w * s)), axis=1)
        dp = half * w * np.stack((-np.sin(w * s), np.cos(w * s)), axis=1)
        ddp = -half * w * w * np.stack((np.cos(w * s), np.sin(w * s)), axis=1)
    elif name == "figure8":
        p = half * np.stack((np.sin(w * s), 0.5 * np.sin(2.0 * w * s)), axis=1)
        dp = half * w * np.stack((np.cos(w * s), np.cos(2.0 * w * s)), axis=1)
        ddp = -half * w * w * np.stack((np.sin(w * s), 2.0 * np.sin(2.0 * w * s)), axis=1)
    else:
        raise SimError(f"unknown shape {name!r}; choose 'circle' or 'figure8'", field="shape")
    return p, dp, ddp


def writing_reference(
    *,
    shape: str = "circle",
    size_m: float = 0.5,
    writing_time_s: float = 6.0,
    start_m_enu: tuple[float, float, float] = (0.0, 0.0, 0.0),
    write_height_m: float = 0.335,
    clearance_m: float = 0.05,
    hold_s: float = 0.5,
    vertical_time_s: float = 1.0,
    rate_hz: float = 100.0,
) -> ReferenceArrays:
    """Hover, descend ``clearance_m``, write ``shape`` of ``size_m`` at ``write_height_m`` above
    the board whose surface passes through ``start_m_enu``, climb, hover."""
    if writing_time_s <= 0.0 or vertical_time_s <= 0.0 or rate_hz <= 0.0 or hold_s < 0.0:
        raise SimError("durations and rate must be positive", field="writing_time_s")
    dt = 1.0 / rate_hz
    bounds = np.cumsum([0.0, hold_s, vertical_time_s, writing_time_s, vertical_time_s, hold_s])
    t = np.arange(round(bounds[-1] * rate_hz) + 1) * dt
    k = t.shape[0]
    p = np.zeros((k, 3))
    v = np.zeros((k, 3))
    a = np.zeros((k, 3))
    z_write = start_m_enu[2] + write_height_m
    p[:, 0], p[:, 1], p[:, 2] = start_m_enu[0], start_m_enu[1], z_write + clearance_m
    for phase, sign in ((1, -1.0), (3, 1.0)):
        m = (t >= bounds[phase]) & (t < bounds[phase + 1])
        s, ds, dds = _min_jerk((t[m] - bounds[phase]) / vertical_time_s)
        p[m, 2] = z_write + clearance_m * (1.0 - s if sign < 0 else s)
        v[m, 2] = sign * clearance_m * ds / vertical_time_s
        a[m, 2] = sign * clearance_m * dds / vertical_time_s**2
    writing = (t >= bounds[2]) & (t <= bounds[3])
    s, ds, dds = _min_jerk((t[writing] - bounds[2]) / writing_time_s)
    q, dq, ddq = _shape(shape, s, size_m)
    p[writing, :2] += q
    p[writing, 2] = z_write
    v[writing, :2] = dq * (ds / writing_time_s)[:, None]
    a[writing, :2] = (
        ddq * (ds / writing_time_s)[:, None] ** 2 + dq * (dds / writing_time_s**2)[:, None]
    )
    after = t > bounds[3]
    p[after, :2] += _shape(shape, np.ones(1), size_m)[0]
    return ReferenceArrays(t, p, v, a, writing)
