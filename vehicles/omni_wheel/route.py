"""Routes between floor areas: checked before a job is accepted, then driven with the marker up.

A route goes sideways on the level it starts on until it is in line with the goal, then straight
along x (steps lie across x), climbing or descending the steps on the way with the proposed wheel
control, then settles on the goal. :func:`check_route` refuses, with one line naming the area and
the step, a route with a step higher than the vehicle climbs, a floor area off the terrain or
straddling a step edge, a floor area whose height is not the floor's, or one too far away.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicles.omni_wheel.model import Terrain
from vehicles.omni_wheel.writing import FloorWriter, OmniSettings

FloatArray = NDArray[np.float64]

MAX_STEP_HEIGHT_M = 0.15
"""Highest step in [m] the writer is allowed to cross (climbed with margin in MuJoCo with rubber
rollers and the proposed method: benchmarks/bench_ground.py)."""
MAX_ROUTE_M = 60.0
"""Longest route in [m] from the start to a floor area."""


class RouteError(ValueError):
    """A floor area the ground writer cannot reach or write on; the message says which and why."""


@dataclass(frozen=True)
class FloorArea:
    """Where a ground writer is sent: a floor area's centre and half size."""

    name: str
    """The area's name in the show."""
    centre_m_enu: tuple[float, float, float]
    """Centre of the area in [m], world ENU (its height must be the floor's there)."""
    half_size_m: float
    """Half the side in [m] of the square the vehicle covers while writing there."""


def check_route(start_m_enu: tuple[float, float, float], area: FloorArea, terrain: Terrain) -> None:
    """Raise :class:`RouteError` when ``area`` cannot be reached from ``start_m_enu`` or written on
    (see the module docstring); return quietly otherwise."""
    x, y, z = area.centre_m_enu
    where = f"floor area {area.name!r}"
    if abs(y) + area.half_size_m > terrain.half_width_m:
        raise RouteError(
            f"{where} at y={y:.2f} m lies off the terrain (|y| <= {terrain.half_width_m:.1f} m)"
        )
    floor = terrain.height_at_m(x)
    if abs(z - floor) > 0.005:
        raise RouteError(
            f"{where} is at height {z:.3f} m but the floor there is {floor:.3f} m high"
        )
    for step in terrain.steps:
        if abs(step.x_m - x) < area.half_size_m:
            raise RouteError(f"{where} straddles the step edge at x={step.x_m:.2f} m")
    length = abs(x - start_m_enu[0]) + abs(y - start_m_enu[1])
    if length > MAX_ROUTE_M:
        raise RouteError(
            f"{where} is out of reach: {length:.1f} m of route, at most {MAX_ROUTE_M:.0f} m"
        )
    lo, hi = sorted((start_m_enu[0], x))
    level = terrain.height_at_m(lo)
    for step in terrain.steps:
        if lo < step.x_m <= hi:
            rise = abs(step.height_m - level)
            if rise > MAX_STEP_HEIGHT_M + 1e-9:
                raise RouteError(
                    f"{where} is out of reach: the step at x={step.x_m:.2f} m is {rise:.3f} m high,"
                    f" the vehicle climbs at most {MAX_STEP_HEIGHT_M:.3f} m"
                )
            level = step.height_m


@dataclass(frozen=True)
class TransitResult:
    """One driven route."""

    arrived: bool
    """The marker settled within the tolerance of the goal before the time ran out."""
    duration_s: float
    """Time in [s] it took (or the time limit)."""
    path_m_enu: FloatArray
    """(K, 3) marker path in [m], ENU (at the floor's height under it)."""
    base_m_enu: FloatArray
    """(K, 3) middle axle centre in [m], ENU (shows the climbs)."""


def _transit_velocity(
    pen_xy: FloatArray, goal_xy: FloatArray, settings: OmniSettings
) -> FloatArray:
    """Marker velocity command in [m/s]: sideways first (on the starting level), then along x."""
    gain = settings.position_gain_per_s
    err = goal_xy - pen_xy
    v0 = settings.geometry.running_speed_mps
    if abs(err[1]) > 0.02:
        return np.array([0.0, float(np.clip(gain * err[1], -0.6 * v0, 0.6 * v0))])
    return np.array([float(np.clip(gain * err[0], -v0, v0)), gain * err[1]])


def drive_route(
    writer: FloorWriter, goal_m_enu: tuple[float, float, float], *, tolerance_m: float = 0.02
) -> TransitResult:
    """Drive ``writer`` with the marker up until its marker settles on ``goal_m_enu``."""
    goal = np.asarray(goal_m_enu[:2], dtype=np.float64)
    s = writer.settings
    start = writer.marker_m_enu()
    budget_s = (
        3.0 * (abs(goal[0] - start[0]) + abs(goal[1] - start[1])) / s.geometry.running_speed_mps
        + 10.0
    )
    t0, path, base = writer.world.t_s, [], []
    while writer.world.t_s - t0 < budget_s:
        pen = writer.measured_marker_xy
        v = _transit_velocity(pen, goal, s)
        # the command is fed forward with the measured marker as its own reference: no correction
        writer.tick(np.array([pen[0], pen[1], 0.0]), np.array([v[0], v[1], 0.0]), False)
        path.append(writer.marker_m_enu())
        base.append(writer.world.truth(0).base_m_enu)
        speed = float(np.linalg.norm(writer.world.truth(0).base_velocity_mps_enu[:2]))
        if math.dist(path[-1][:2], goal) < tolerance_m and speed < 0.02:
            return TransitResult(True, writer.world.t_s - t0, np.array(path), np.array(base))
    return TransitResult(False, writer.world.t_s - t0, np.array(path), np.array(base))
