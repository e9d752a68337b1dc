"""The time law: the fitted path flown as fast as its limits allow, then fitted again in time.

The minimum-jerk fit (planner.timescale) times its path with the spline itself: its acceleration
is linear between knots 0.2 s apart and passes through zero between an acceleration and the
next braking, so it flies 1.06-1.19x the time-optimal duration of its own path after 10
per-segment rounds (TOPP-RA, planner.timeopt_reference; median 1.15, worst 1.26 after the 3 it
has now). Here the path stays and only its timing changes: the fit ``p(tau)``,
``tau`` its own time, is flown as ``q(t) = p(tau(t))``.

With ``b(tau) = (dtau/dt)^2`` (the squared path speed of time-optimal path parameterisation:
Bobrow et al. 1985; convex in ``b``, Verscheure et al. 2009, IEEE TAC 54(10)) the flight's
acceleration and squared speed are linear in ``b``::

    q'' = p''(tau) b + p'(tau) b' / 2        |q'|^2 = |p'(tau)|^2 b

``b`` is a cubic B-spline on the fit's knots (so ``q''`` is continuous and the jerk bounded),
chosen by one QP: the largest ``int b dtau`` (the first-order decrease of the flight time
``int b^(-1/2) dtau`` at ``b = 1``) less ``SMOOTHING`` times the squared second differences of
its control points, with every per-axis acceleration bound and the speed limit imposed at
``SAMPLES_PER_SPAN`` points per span and ``b`` within ``RATE_SQUARED_RANGE``. The flight is then
fitted as a clamped uniform cubic spline again, with ``KNOTS_PER_SPAN`` knots for each of the
fit's spans (closed form, rest to rest, on ``FIT_SAMPLES_PER_KNOT`` samples of ``q`` per knot;
within 0.03 mm of it), its z control points held at the floor, and uniformly re-timed so
that its exact limits (acceleration at the knots, speed on the hodograph, as planner.timescale
reads them) are just reached. It is kept when it is shorter.

Measured on ``bench_planner``'s corpus and held-out set (220 characters; ratio to TOPP-RA on the
same path, median / worst; 2026-12-02, one core): the fit's own timing 1.15 / 1.26 (3 per-segment
rounds of planner.timescale), the flight 1.071 / 1.136 (``j``), every character's flight kept
(figures below with 5 rounds: 1.069 / 1.138). Its jerk grows (59 of them): the largest per character
median 3.4 -> 5.6 m/s^3, the body-rate bound of eq. (15) median 0.55 -> 0.88 rad/s (at most 1.13,
against 3). Tried: ``SMOOTHING`` 1 and 10: 1.061 / 1.121 (jerk median 6.9 m/s^3, body rate up to
1.41 rad/s) and 1.080 / 1.150; 3 samples per span: no change; knots of the flight 2, 4 per span:
1.071 / 1.141 and 1.066 / 1.135 (with ``SMOOTHING`` 1 and 2 knots per span 66 of the 220 flights
came out no shorter than their fit, their acceleration missed by the coarser spline in ``t`` at the
jerk's jumps and the re-timing taking that back from the whole flight); ``b`` on a coarser spline
(every second knot of the fit): 1.080-1.091 / 1.146-1.171.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from planner.bspline import (
    ClampedCubicSpline,
    FloatArray,
    IntArray,
    basis_rows,
    basis_rows_pair,
)
from planner.coo import CooMatrix, vstack
from planner.minjerk import EndState, FitProblem, closed_form_points
from planner.qp_solvers import QpData, QpSolution
from planner.qp_structure import QpLimits
from planner.timescale import time_factors

SAMPLES_PER_SPAN = 2
"""Points per span of the fit at which the QP imposes the limits (between them the flight may
exceed a bound slightly; the final re-timing reads the limits exactly)."""
SMOOTHING = 3.0
"""Weight of the squared second differences of ``b``'s control points against ``int b dtau``,
per second of the fit (the module docstring gives 1 and 10)."""
RATE_SQUARED_RANGE = (0.5, 4.0)
"""Bounds of ``b``: no part of the path flown slower than 0.71x or faster than 2x the fit's own
timing (at the rest ends, where no limit binds, ``b`` reaches the upper bound; the jerk grows
with ``b^1.5``)."""
KNOTS_PER_SPAN = 3
"""Knots of the flight's spline per span of the fit (0.067 s at the fit's 0.2 s)."""
FIT_SAMPLES_PER_KNOT = 2
"""Samples of the flight per knot of its spline, fitted in the closed form."""
FIT_JERK_WEIGHT_S5 = 1e-12
"""``w_g`` of that fit, [s^5]: small against the samples (the samples alone determine it)."""
GRID_PER_SPAN = 16
"""Points per span of the fit at which ``t(tau)`` is integrated (trapezoid)."""

Solve = Callable[[QpData], QpSolution]
_NO_INDEX = np.zeros(0, dtype=np.int64)


def _rows_that_can_bind(
    first: IntArray, values: FloatArray, lower: float, upper: float, n_ctrl: int
) -> tuple[CooMatrix, FloatArray, FloatArray]:
    """Rows ``values[k, a]`` at columns ``first[k] + a`` (4 per row) with their bounds, only
    those some ``b`` within ``RATE_SQUARED_RANGE`` could take past a bound (the others hold
    for every ``b`` the QP may choose: the z rows of a flat board, slow parts' speed rows)."""
    lo, hi = RATE_SQUARED_RANGE
    reach_hi = np.sum(np.maximum(values * lo, values * hi), axis=1)
    reach_lo = np.sum(np.minimum(values * lo, values * hi), axis=1)
    keep = np.flatnonzero((reach_hi > upper) | (reach_lo < lower))
    rows = CooMatrix(
        rows=np.repeat(np.arange(keep.shape[0], dtype=np.int64), 4),
        cols=(first[keep, None] + np.arange(4)[None, :]).ravel(),
        values=values[keep].ravel(),
        shape=(keep.shape[0], n_ctrl),
    )
    return rows, np.full(keep.shape[0], lower), np.full(keep.shape[0], upper)


def rate_qp(spline: ClampedCubicSpline, limits: QpLimits) -> QpData:
    """The QP of ``b``'s control points for ``spline`` (see the module docstring)."""
    m, alpha, duration = spline.n_spans, spline.alpha, spline.duration_s
    n = m + 3
    tau = np.linspace(0.0, duration, SAMPLES_PER_SPAN * m + 1)
    value, slope = basis_rows_pair(alpha * tau, m)
    d1, d2 = spline.evaluate(tau, 1), spline.evaluate(tau, 2)
    parts = [  # q'' = p'' b + p' b' / 2 per axis, b' = alpha db/du
        _rows_that_can_bind(
            value.first,
            d2[:, [k]] * value.values + 0.5 * alpha * d1[:, [k]] * slope.values,
            limits.accel_lower_mps2[k],
            limits.accel_upper_mps2[k],
            n,
        )
        for k in range(3)
    ]
    if limits.speed_max_mps is not None:  # |q'|^2 = |p'|^2 b
        speed_sq = np.sum(d1 * d1, axis=1)[:, None] * value.values
        parts.append(
            _rows_that_can_bind(value.first, speed_sq, -np.inf, limits.speed_max_mps**2, n)
        )
    weights = np.full(tau.shape[0], duration / (tau.shape[0] - 1))
    weights[[0, -1]] *= 0.5
    c = -np.bincount(
        (value.first[:, None] + np.arange(4)).ravel(),
        weights=(weights[:, None] * value.values).ravel(),
        minlength=n,
    ).astype(np.float64)
    return QpData(
        P_upper=_smoothing_upper(n, SMOOTHING * duration / n),
        c=c,
        A=CooMatrix(_NO_INDEX, _NO_INDEX, np.zeros(0), (0, n)),
        b=np.zeros(0),
        G=vstack([rows for rows, _, _ in parts]),
        h_l=np.concatenate([lower for _, lower, _ in parts]),
        h_u=np.concatenate([upper for _, _, upper in parts]),
        x_l=np.full(n, RATE_SQUARED_RANGE[0]),
        x_u=np.full(n, RATE_SQUARED_RANGE[1]),
    )


def _smoothing_upper(n: int, weight: float) -> CooMatrix:
    """Upper triangle of ``weight * D2^T D2`` (``D2`` the second differences of ``n`` values)."""
    diag = np.full(n, 6.0)
    diag[[0, -1]], diag[[1, -2]] = 1.0, 5.0
    first = np.full(n - 1, -4.0)
    first[[0, -1]] = -2.0
    rows = np.concatenate([np.arange(n), np.arange(n - 1), np.arange(n - 2)])
    cols = np.concatenate([np.arange(n), np.arange(1, n), np.arange(2, n)])
    values = weight * np.concatenate([diag, first, np.ones(n - 2)])
    order = np.lexsort((cols, rows))
    return CooMatrix(rows[order], cols[order], values[order], (n, n))


class Flight:
    """The path of a fit flown on a time law: its spline and the flight time of every path
    time."""

    def __init__(
        self, spline: ClampedCubicSpline, path_grid_s: FloatArray, flight_grid_s: FloatArray
    ) -> None:
        self.spline = spline
        """The flight ``q(t)``, a clamped uniform cubic spline in its own time."""
        self._path_grid_s = path_grid_s
        self._flight_grid_s = flight_grid_s

    def flight_time_s(self, path_time_s: FloatArray) -> FloatArray:
        """When the flight passes where the fit was at ``path_time_s``, [s]."""
        return np.asarray(np.interp(path_time_s, self._path_grid_s, self._flight_grid_s))


def fly_at_limits(spline: ClampedCubicSpline, limits: QpLimits, solve: Solve) -> Flight | None:
    """The flight of ``spline``'s path on the fastest smooth time law (module docstring), or
    ``None`` when it would not be shorter (or the QP found none)."""
    solution = solve(rate_qp(spline, limits))
    if solution.status != "solved":
        return None
    m, alpha = spline.n_spans, spline.alpha
    tau = np.linspace(0.0, spline.duration_s, GRID_PER_SPAN * m + 1)
    rate_sq = np.maximum(basis_rows(alpha * tau, m).apply(solution.x), RATE_SQUARED_RANGE[0])
    slowness = 1.0 / np.sqrt(rate_sq)  # dt/dtau
    t_grid = np.concatenate([[0.0], np.cumsum(0.5 * (slowness[1:] + slowness[:-1]) * np.diff(tau))])
    flown = _fitted_in_time(spline, tau, t_grid, KNOTS_PER_SPAN * m, limits.z_floor_m)
    _, factors = time_factors(flown, limits)
    stretch = float(np.max(factors))
    if not stretch * flown.duration_s < spline.duration_s:
        return None
    timed = ClampedCubicSpline(flown.control_points, flown.duration_s * stretch)
    return Flight(timed, tau, t_grid * stretch)


def _fitted_in_time(
    spline: ClampedCubicSpline,
    path_grid_s: FloatArray,
    flight_grid_s: FloatArray,
    n_spans: int,
    z_floor_m: float | None,
) -> ClampedCubicSpline:
    """``q(t) = p(tau(t))`` as a clamped uniform cubic spline of ``n_spans`` spans, rest to rest,
    its z control points no lower than ``z_floor_m`` (so the flight stays above it)."""
    duration = float(flight_grid_s[-1])
    t = np.linspace(0.0, duration, FIT_SAMPLES_PER_KNOT * n_spans + 1)
    points = spline.evaluate(np.interp(t, flight_grid_s, path_grid_s))
    problem = FitProblem(
        times_s=t,
        points_m=points,
        weights=np.ones(t.shape[0]),
        n_spans=n_spans,
        duration_s=duration,
        jerk_weight_s5=FIT_JERK_WEIGHT_S5,
        start=EndState(points[0]),
        end=EndState(points[-1]),
    )
    control, _ = closed_form_points(problem)
    if z_floor_m is not None:
        control[:, 2] = np.maximum(control[:, 2], z_floor_m)
    return ClampedCubicSpline(control, duration)
