"""Time-optimal times along the data polyline: the start of the time allocation at the limits.

The data points of a character (planner.waypoints) form a polyline. Along it, the fastest rest-to-
rest motion under the vehicle limits is found by the classic forward-backward pass: each piece
``j`` (direction ``u_j``, length ``L_j``) gets the largest acceleration the per-axis bounds allow
along ``u_j`` and the speed limit ``v_max`` (a ball, as planner.timescale reads it); each vertex
gets a speed limit from its turn (the velocity turns by ``2 v sin(theta/2)`` within about one
smoothing time ``corner_time_s`` at that acceleration), zero at a repeated point (a dwell) and at
the ends. Each piece is then flown accelerate-cruise-decelerate between its vertex speeds.

This is bang-bang timing of a path with corners; the minimum-jerk fit smooths both, and
planner.timescale re-times the result until the fit is within the limits everywhere.
"""

from __future__ import annotations

import math

import numpy as np

from planner.bspline import FloatArray
from planner.qp_structure import QpLimits


def _along(limits: QpLimits, u: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Per piece direction (n, 3): largest |acceleration| and speed along it."""
    bound = np.minimum(-np.asarray(limits.accel_lower_mps2), np.asarray(limits.accel_upper_mps2))
    with np.errstate(divide="ignore"):
        accel = np.min(np.where(np.abs(u) > 1e-12, bound / np.abs(u), np.inf), axis=1)
    if limits.speed_max_mps is None:
        return accel, np.full(u.shape[0], np.inf)
    return accel, np.full(u.shape[0], limits.speed_max_mps)


def _vertex_speeds(
    u: FloatArray, accel: FloatArray, length: FloatArray, corner_time_s: float
) -> FloatArray:
    """Speed limit at every vertex (n + 1,): 0 at the ends and around zero-length pieces."""
    n = u.shape[0]
    limit = np.zeros(n + 1)
    turn = np.linalg.norm(u[1:] - u[:-1], axis=1)  # = 2 sin(theta / 2)
    a = np.minimum(accel[1:], accel[:-1])
    with np.errstate(divide="ignore"):
        limit[1:-1] = np.where(turn > 1e-9, a * corner_time_s / turn, np.inf)
    still = length <= 1e-12
    limit[:-1][still] = 0.0
    limit[1:][still] = 0.0
    return limit


def _piece_times_s(
    v_a: FloatArray, v_b: FloatArray, length: FloatArray, a: FloatArray, v_max: FloatArray
) -> FloatArray:
    """Per piece: accelerate from ``v_a``, cruise at most ``v_max``, decelerate to ``v_b`` over
    ``length`` (0 for a piece of no length)."""
    ends2 = v_a * v_a + v_b * v_b
    peak = np.minimum(v_max, np.sqrt(np.maximum(a * length + 0.5 * ends2, 0.0)))
    peak = np.maximum(peak, np.maximum(v_a, v_b))
    ramps = (2.0 * peak * peak - ends2) / (2.0 * a)
    moving = peak > 0.0
    cruise = np.where(moving, np.maximum(length - ramps, 0.0) / np.where(moving, peak, 1.0), 0.0)
    times = (2.0 * peak - v_a - v_b) / a + cruise
    return np.asarray(np.where(length > 0.0, times, 0.0))


def polyline_durations_s(
    points_m: FloatArray,
    limits: QpLimits,
    *,
    corner_time_s: float,
    min_duration_s: float,
) -> FloatArray:
    """Time-optimal duration of every piece of the polyline ``points_m`` (N, 3), shape (N - 1,)."""
    delta = np.diff(points_m, axis=0)
    length = np.linalg.norm(delta, axis=1)
    u = np.divide(delta, length[:, None], out=np.zeros_like(delta), where=length[:, None] > 0.0)
    accel, speed = _along(limits, u)
    accel = np.where(np.isfinite(accel), accel, 1.0)
    v = np.minimum(_vertex_speeds(u, accel, length, corner_time_s), np.append(speed, 0.0))
    v = np.minimum(v, np.concatenate([[0.0], speed]))
    # the passes run on Python floats (the same IEEE arithmetic, without numpy's scalar costs)
    vs, a_l, l_l = v.tolist(), accel.tolist(), length.tolist()
    n = len(l_l)
    for j in range(n):  # forward: reachable from the previous vertex
        vs[j + 1] = min(vs[j + 1], math.sqrt(vs[j] ** 2 + 2.0 * a_l[j] * l_l[j]))
    for j in range(n - 1, -1, -1):  # backward: can still stop in time
        vs[j] = min(vs[j], math.sqrt(vs[j + 1] ** 2 + 2.0 * a_l[j] * l_l[j]))
    ends = np.array(vs)
    times = _piece_times_s(ends[:-1], ends[1:], length, accel, speed)
    return np.asarray(np.maximum(times, min_duration_s), dtype=np.float64)
