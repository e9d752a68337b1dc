"""Safety net: where the written path strays from the strokes, tighten the fit there and re-solve.

The data path (planner.waypoints) keeps the pen-down path within a few millimetres of the strokes
for the usual sizes and limits. Where it does not -- large or dense characters, a heavy jerk
weight, tight limits or a short fixed total time -- each stroke whose worst stray exceeds
``REFINE_TARGET`` of the tolerance is tightened locally: the data points around the time of the
stray weigh ``WEIGHT_GAIN`` times more and the segments between them take ``TIME_STRETCH`` times
longer (with a fixed total time the other segments give that time back), then the fit is solved
again with the same limits. At most ``REFINE_ROUNDS`` rounds; the best fit seen is kept, so the
caller raises only when no round brought the path within the tolerance.

A stray is measured as in the feasibility report: the horizontal distance of the pen-down
reference (within a stroke's window, at most ``pen_contact_tolerance_m`` above writing height,
sampled at 100 Hz) from the polyline through the stroke's turning points, and the distance of
the path from each turning point at its data time.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.board import BoardFrame
from planner.bspline import ClampedCubicSpline, FloatArray
from planner.errors import InfeasibleTrajectoryError
from planner.feasibility import located_path_errors
from planner.fit_qp import diagnose_infeasible
from planner.minjerk import FitProblem, SplineFit
from planner.qp_structure import QpLimits
from planner.waypoints import KIND_TURNING, WritingPath

REFINE_ROUNDS = 6
"""Most tighten-and-re-solve rounds (each costs one fit, a few ms)."""
REFINE_TARGET = 0.8
"""Strokes straying more than this fraction of the tolerance are tightened in a round."""
WEIGHT_GAIN = 3.0
"""Factor on the weights of the data points around a stray, per round."""
TIME_STRETCH = 1.3
"""Factor on the durations of the segments around a stray, per round."""
NEIGHBOURS = 2
"""Data points on each side of a stray's time that are tightened."""
SAMPLE_DT_S = 0.01
"""Sampling step of the pen-down path check, [s]."""


@dataclass(frozen=True)
class StrokeErrors:
    """How far each stroke's written path strays from its turning-point polyline."""

    path_m: tuple[float, ...]
    """Per stroke: largest horizontal distance of the pen-down path from the polyline, [m]."""
    turning_m: tuple[float, ...]
    """Per stroke: largest distance of the path from a turning point at its time, [m]."""
    worst_t_s: tuple[float, ...]
    """Per stroke: time of the larger of the two, [s]."""
    spots: tuple[tuple[float, float], ...] = ()
    """Every place worth tightening: (error [m], time [s]) of each turning point and of the
    worst pen-down sample of each stroke."""

    @property
    def per_stroke_m(self) -> tuple[float, ...]:
        """Per stroke: the larger of the path and turning-point errors, [m]."""
        return tuple(max(p, q) for p, q in zip(self.path_m, self.turning_m, strict=True))

    @property
    def worst_m(self) -> float:
        """Largest error over all strokes, [m]."""
        return max(self.per_stroke_m, default=0.0)


def stroke_intervals(path: WritingPath, times_s: FloatArray) -> tuple[tuple[float, float], ...]:
    """Per stroke: times of its approach and lift points, [s] (the pen may touch between)."""
    return tuple((float(times_s[a]), float(times_s[b])) for a, b in path.pen_windows)


def measure(
    spline: ClampedCubicSpline,
    problem: FitProblem,
    residuals_m: FloatArray,
    path: WritingPath,
    board: BoardFrame,
    pen_contact_tolerance_m: float,
) -> StrokeErrors:
    """Pen-down path errors and turning-point residuals per stroke, with the time of the worst."""
    t = np.arange(0.0, spline.duration_s, SAMPLE_DT_S)
    p = spline.evaluate(t)
    pen = p[:, 2] <= path.write_z_m + pen_contact_tolerance_m
    polylines = tuple(board.to_world(tp)[:, :2] for tp in path.turning_points_board_m)
    located = located_path_errors(p, t, pen, stroke_intervals(path, problem.times_s), polylines)
    dist = np.linalg.norm(residuals_m, axis=1)
    turning = path.kinds == KIND_TURNING
    turning_m, worst_t = [], []
    for k, (error, t_error) in enumerate(located):
        idx = np.flatnonzero(turning & (path.stroke_of_point == k))
        i = int(idx[np.argmax(dist[idx])]) if idx.size else -1
        residual = float(dist[i]) if i >= 0 else 0.0
        turning_m.append(residual)
        worst_t.append(float(problem.times_s[i]) if residual > error else t_error)
    spots = [*located, *zip(dist[turning].tolist(), problem.times_s[turning].tolist(), strict=True)]
    return StrokeErrors(
        path_m=tuple(e for e, _ in located),
        turning_m=tuple(turning_m),
        worst_t_s=tuple(worst_t),
        spots=tuple(spots),
    )


def tighten(
    problem: FitProblem,
    errors: StrokeErrors,
    target_m: float,
    *,
    fixed_total: bool,
    min_duration_s: float,
) -> tuple[FloatArray, FloatArray] | None:
    """New (weights, segment durations) tightening the fit around each spot above ``target_m``.

    ``None`` when no spot is above target. With a fixed total time the other segments give the
    time back (none below ``min_duration_s``); when they cannot, only the weights change.
    """
    times = problem.times_s
    durations = problem.segment_durations()
    points = np.zeros(times.shape[0], dtype=bool)
    segments = np.zeros(durations.shape[0], dtype=bool)
    for error, t_s in errors.spots:
        if error <= target_m:
            continue
        i = int(np.clip(np.searchsorted(times, t_s, side="right") - 1, 0, durations.shape[0] - 1))
        lo, hi = max(0, i - NEIGHBOURS + 1), min(times.shape[0], i + NEIGHBOURS + 1)
        points[lo:hi] = True
        segments[lo : hi - 1] = True
    if not np.any(points):
        return None
    weights = np.where(points, problem.weights * WEIGHT_GAIN, problem.weights)
    new = np.where(segments, durations * TIME_STRETCH, durations)
    if fixed_total:  # the others give the time back in proportion to their slack
        needed = float(np.sum(new - durations))
        slack = np.where(segments, 0.0, np.maximum(durations - min_duration_s, 0.0))
        if float(np.sum(slack)) <= needed:
            return weights, durations  # no time to spare: re-weight only
        new = new - slack * (needed / float(np.sum(slack)))
    return weights, new


@dataclass(frozen=True, eq=False)
class Refinement:
    """Outcome of :func:`refine`: the best fit seen and its errors."""

    problem: FitProblem
    """Problem (weights, times) of the best fit."""
    fit: SplineFit
    """The best fit (smallest worst error)."""
    errors: StrokeErrors
    """Its per-stroke errors."""
    rounds: int
    """Rounds of tightening that were solved."""


def refine(
    problem: FitProblem,
    fit: SplineFit,
    errors_of: Callable[[FitProblem, SplineFit], StrokeErrors],
    solve: Callable[[FitProblem], SplineFit],
    rebuild: Callable[[FitProblem, FloatArray, FloatArray], FitProblem],
    *,
    tolerance_m: float,
    fixed_total: bool,
    min_duration_s: float,
) -> Refinement:
    """Tighten and re-solve until every stroke is within ``tolerance_m`` (see module docstring).

    ``rebuild(problem, weights, durations)`` makes the next problem; ``solve`` fits it under the
    limits (an :class:`InfeasibleTrajectoryError` ends the rounds).
    """
    errors = errors_of(problem, fit)
    best = Refinement(problem, fit, errors, 0)
    current = best
    for rounds in range(1, REFINE_ROUNDS + 1):
        if best.errors.worst_m <= tolerance_m:
            break
        change = tighten(
            current.problem,
            current.errors,
            REFINE_TARGET * tolerance_m,
            fixed_total=fixed_total,
            min_duration_s=min_duration_s,
        )
        if change is None:
            break
        candidate = rebuild(current.problem, *change)
        try:
            new_fit = solve(candidate)
        except InfeasibleTrajectoryError:
            break
        current = Refinement(candidate, new_fit, errors_of(candidate, new_fit), rounds)
        if current.errors.worst_m < best.errors.worst_m:
            best = current
    return Refinement(best.problem, best.fit, best.errors, current.rounds)


def stray_error(
    problem: FitProblem, limits: QpLimits, errors: StrokeErrors, tolerance_m: float
) -> InfeasibleTrajectoryError:
    """The error to raise when ``errors`` exceed the tolerance after :func:`refine`.

    It names the limit the unconstrained fit would break (the limits are what pulls the path
    off the strokes), or ``"fit_error"`` with the stroke and time of the worst stray.
    """
    per_stroke = errors.per_stroke_m
    stroke = int(np.argmax(per_stroke))
    error_m = per_stroke[stroke]
    shape = (
        f"the path strays {error_m * 1e3:.0f} mm from the stroke (> {tolerance_m * 1e3:.0f} mm)"
        f" even after {REFINE_ROUNDS} rounds of local re-weighting and re-timing"
    )
    cause = diagnose_infeasible(problem, limits)
    if abs(cause.value) > abs(cause.bound):  # the free fit breaks a limit: that is the cause
        return InfeasibleTrajectoryError(
            f"{shape}: the path along the strokes would break the {cause.message}",
            limit=cause.limit,
            axis=cause.axis,
            t_s=cause.t_s,
            value=cause.value,
            bound=cause.bound,
            stroke_index=stroke,
        )
    return InfeasibleTrajectoryError(
        f"{shape}; allow more time, lower the jerk weight or raise the tolerance",
        limit="fit_error",
        axis=None,
        t_s=errors.worst_t_s[stroke],
        value=error_m,
        bound=tolerance_m,
        stroke_index=stroke,
    )
