"""Our extension of eq. 7: the pen stays on the stroke between waypoints, not only at them.

The paper pins positions at the waypoints only (eq. 7d). Between two waypoints the optimum of
eq. 7a (time, speed, control effort) then cuts and swings: on 1 m letters at 20 cm/s and
20 cm/s^2 the planned pen path left the strokes by up to 29.6 mm (永), 15.7 mm (8). Here each
node of a contact period between waypoints ``i`` and ``i + 1`` is held in a corridor around
their chord: within ``half_width_m`` across it and between its ends along it (two linear
constraint rows per node, ``period_nlp``): within ``half_width_m`` across the parabola through
the two waypoints that fits the stroke between them (``Period.sagitta_m``; a chord of a curve
lies on its inner side, by up to the thinning tolerance, and a pen riding the inner edge of a
corridor around the chord lays its line off the target's by a millimetre or two: IoU 0.79 on
the 1 m "8" with chords, 2 mm corridors), and between the chord's ends along it. The reference
between nodes is their linear interpolation, a chord of the planned path.

A corridor makes corners slow: the pen must turn by the angle between two chords without
leaving either corridor. :func:`segment_times_s` allots each segment the time of a trapezoidal
speed profile under the corner speeds :func:`corner_speeds_mps` allow, so that a period gets
enough steps of at most ``h_max`` for it (the paper's count, distance over speed, leaves a
spiral or a cursive word infeasible). ``Limits.corridor_m = None`` is the paper's eq. 7.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.waypoints import Period

FloatArray = NDArray[np.float64]

LATERAL_SHARE = 0.8
"""Share of ``a_max`` a turn is allotted in :func:`corner_speeds_mps` and on a parabola (the
rest is left for speeding up and slowing down along the path)."""
CORNER_RADIUS_SHARE = 1.0
"""Share of the largest turning radius inside both corridors (:func:`corner_speeds_mps`) a
corner is allotted. The three shares are fitted to the optimum: on the 1 m "8" (a 30-gon, every
corner a turn) the least times of its chords came within -30 %..+6 % of the planned ones
(0.5 here and in :data:`LATERAL_SHARE`, 0.7 in :data:`ALONG_SHARE`: up to 1.5x the planned,
and IPOPT solved a quarter more steps than needed)."""
ALONG_SHARE = 0.9
"""Share of ``a_max`` speeding up or slowing down along a segment in :func:`segment_times_s`."""
SHORTEST_CHORD_M = 1e-9
"""A chord shorter than this in [m] has no direction (pressing or lifting in place)."""


def chords(points_xy_m: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Lengths (M-1,) in [m] and unit directions (M-1, 2) of the chords between waypoints
    (M, 2); a chord without length gets the direction (1, 0)."""
    delta = np.diff(points_xy_m, axis=0)
    length = np.linalg.norm(delta, axis=1)
    direction = np.tile([1.0, 0.0], (length.size, 1))
    long = length > SHORTEST_CHORD_M
    direction[long] = delta[long] / length[long, None]
    return length, direction


def _headings_rad(period: Period) -> tuple[FloatArray, FloatArray]:
    """(M-1,) heading in [rad] of each chord's parabola where it leaves its first waypoint and
    where it reaches its second (the chord's heading -+ atan(4 sagitta / length))."""
    length, direction = chords(period.points_m[:, 0:2])
    chord = np.arctan2(direction[:, 1], direction[:, 0])
    slope = np.arctan(4.0 * period.sagittas_m() / np.maximum(length, SHORTEST_CHORD_M))
    return chord + slope, chord - slope


def turns_rad(period: Period) -> FloatArray:
    """(M-2,) angle in [0, pi] [rad] the path turns by at each inner waypoint, from the end
    heading of one chord's parabola to the start heading of the next."""
    leave, reach = _headings_rad(period)
    turn = np.mod(leave[1:] - reach[:-1] + np.pi, 2.0 * np.pi) - np.pi
    return np.asarray(np.abs(turn), dtype=np.float64)


def corner_speeds_mps(
    period: Period, half_width_m: float, v_max_mps: float, a_max_mps2: float
) -> FloatArray:
    """(M,) speed limit in [m/s] at each waypoint of a contact period with corridors of
    ``half_width_m``: 0 at both ends and beside a chord without length; where the path turns by
    ``theta`` (from one parabola's end heading to the next one's start), an arc through the
    waypoint inside both corridors has a radius of at most ``half_width / (1 - cos(theta/2))``
    (its sagitta over either), and the speed on a share of it under a share of ``a_max`` is
    the limit."""
    length, _ = chords(period.points_m[:, 0:2])
    speeds = np.full(length.size + 1, v_max_mps)
    speeds[[0, -1]] = 0.0
    theta = turns_rad(period)
    sagitta_per_radius = 1.0 - np.cos(0.5 * theta)
    with np.errstate(divide="ignore"):
        radius = CORNER_RADIUS_SHARE * half_width_m / sagitta_per_radius
    turn = np.sqrt(LATERAL_SHARE * a_max_mps2 * radius)
    still = (length[:-1] <= SHORTEST_CHORD_M) | (length[1:] <= SHORTEST_CHORD_M)
    speeds[1:-1] = np.where(still, 0.0, np.minimum(turn, v_max_mps))
    return speeds


def segment_times_s(
    period: Period, half_width_m: float, v_max_mps: float, a_max_mps2: float
) -> FloatArray:
    """(M-1,) time in [s] of each chord of a contact period: a trapezoidal speed profile under
    ``v_max`` and the parabola's own curvature (``8 sagitta / length^2``) at a share of
    ``a_max``, speeding up and slowing down at a share of ``a_max``, within the corner speeds
    (made reachable from rest at both ends by a forward and a backward pass)."""
    length, _ = chords(period.points_m[:, 0:2])
    curvature = 8.0 * np.abs(period.sagittas_m()) / np.maximum(length, SHORTEST_CHORD_M) ** 2
    with np.errstate(divide="ignore"):
        cap = np.minimum(v_max_mps, np.sqrt(LATERAL_SHARE * a_max_mps2 / curvature))
    speeds = corner_speeds_mps(period, half_width_m, v_max_mps, a_max_mps2)
    speeds[:-1] = np.minimum(speeds[:-1], cap)
    speeds[1:] = np.minimum(speeds[1:], cap)
    a = ALONG_SHARE * a_max_mps2
    for i in range(length.size):
        speeds[i + 1] = min(speeds[i + 1], math.sqrt(speeds[i] ** 2 + 2.0 * a * length[i]))
    for i in range(length.size - 1, -1, -1):
        speeds[i] = min(speeds[i], math.sqrt(speeds[i + 1] ** 2 + 2.0 * a * length[i]))
    return np.array(
        [
            _trapezoid_s(float(d), speeds[i], speeds[i + 1], float(cap[i]), a)
            for i, d in enumerate(length)
        ]
    )


def _trapezoid_s(length_m: float, v0: float, v1: float, v_max: float, a: float) -> float:
    """Least time in [s] over ``length_m`` from speed ``v0`` to ``v1`` (both at most
    ``v_max``, reachable from each other) within ``v_max`` at acceleration ``a``."""
    peak = min(v_max, math.sqrt(max(0.5 * (v0**2 + v1**2) + a * length_m, 0.0)))
    ramps_m = (2.0 * peak**2 - v0**2 - v1**2) / (2.0 * a)
    cruise_s = max(length_m - ramps_m, 0.0) / max(peak, 1e-9)
    return (2.0 * peak - v0 - v1) / a + cruise_s


CORRIDOR_PARAMETERS = 7
"""Parameters of a node's corridor: the chord's left normal (2) and direction (2), where the
chord starts along its direction in [m], its length in [m] and the parabola's ``4 sagitta /
length^2`` in [1/m]."""


def corridor_rows(
    period: Period, nodes: NDArray[np.int_], half_width_m: float | None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Per node ``0..n-1`` of ``period`` (waypoints at ``nodes``): its corridor's parameters
    (n, :data:`CORRIDOR_PARAMETERS`) and the bounds (n, 2) in [m] of its rows: across, the
    offset ``normal . p - k u (length - u)`` with ``u = direction . p - start`` (the node's
    offset from the parabola plus the chord's own offset), along, ``direction . p``. Free
    flight, or no ``half_width_m`` (the paper's eq. 7): unbounded."""
    n = int(nodes[-1])
    rows = np.zeros((n, CORRIDOR_PARAMETERS))
    lower = np.full((n, 2), -np.inf)
    upper = np.full((n, 2), np.inf)
    if half_width_m is None or not period.contact:
        return rows, lower, upper
    start = period.points_m[:-1, 0:2]
    length, direction = chords(period.points_m[:, 0:2])
    normal = np.column_stack([-direction[:, 1], direction[:, 0]])
    bend = 4.0 * period.sagittas_m() / np.maximum(length, SHORTEST_CHORD_M) ** 2
    segment = np.repeat(np.arange(length.size), np.diff(nodes))
    across = np.einsum("ij,ij->i", normal, start)[segment]
    along = np.einsum("ij,ij->i", direction, start)[segment]
    rows[:, 0:2], rows[:, 2:4] = normal[segment], direction[segment]
    rows[:, 4], rows[:, 5], rows[:, 6] = along, length[segment], bend[segment]
    lower[:, 0], upper[:, 0] = across - half_width_m, across + half_width_m
    lower[:, 1], upper[:, 1] = along, along + length[segment]
    return rows, lower, upper
