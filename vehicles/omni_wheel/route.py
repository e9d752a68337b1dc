"""Routes between floor areas: checked before a job is accepted, then driven with the marker up.

A route goes sideways on the level it starts on until it is in line with the goal, then straight
along x (steps lie across x), climbing or descending the steps on the way with the proposed wheel
control, then settles on the goal (the live agent's pen-up moves take the same shape:
``JobPhases.route``). :func:`check_route` (light, in ``check_route.py`` so the show file can
read it) refuses, in one line naming the area and the step, a floor area the vehicle cannot reach.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicles.omni_wheel.floor_plan import OmniSettings
from vehicles.omni_wheel.writing import FloorWriter

FloatArray = NDArray[np.float64]


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
