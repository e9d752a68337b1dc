"""Strokes on a board -> one flyable, checked, minimum-jerk trajectory (the Airshow planner).

Stages (each timed in ``PlannedTrajectory.timing_ms``):

1. ``path``: split-and-merge turning points per stroke, pen up/down data path, nominal times;
2. ``initial_times``: scaled to a fixed total time, or with a free total time (pace ``"limits"``,
   the default) time-optimal along the data polyline and scaled until the binding limit is
   just active (planner.timing);
3. ``resegment`` (optional): at pace ``"limits"`` per-segment re-timing until every part of the
   path flies at its binding limit (planner.timescale); otherwise the paper's optimal time
   re-segmentation (planner.retime);
4. ``fit``: the QP with acceleration, speed and floor limits (or the closed form); the paper's
   re-segmentation ends with it (its last solve is the final fit);
5. ``time_law`` (pace ``"limits"``, free total time, the QP method): the fit's path flown as
   fast as its limits allow on a smooth time law and fitted again in time, with knots a third as
   far apart (planner.time_law); kept when shorter, within ``fit_tolerance_m`` of the strokes and
   within every limit, all measured on the flight itself;
6. ``refine`` (when no flight was kept): the pen-down path is measured against the strokes;
   where it strays beyond ``fit_tolerance_m`` the fit is tightened locally and solved again
   (planner.refine) and flown as it is (a fit that strays at pace ``"limits"`` is rare: none
   of ``bench_planner``'s 220 characters);
7. ``feasibility``: report, and :class:`InfeasibleTrajectoryError` if any limit is exceeded or
   the path still strays (naming the limit that pulls it off the strokes, if one does).

Spline size: uniform knots ``knot_spacing_s`` apart (default 0.2 s: 5 control points per second
per axis, finer than the shortest leg time ``min_leg_time_s`` of the path), at least 8 spans; the
flight of stage 5 has three times as many.
Jerk weight: ``w_g = jerk_weight_s5`` (default 1e-4 s^5): for 1 m characters flown at the
default limits the pen-down path stays within about 1 cm of the strokes (median of the largest
error per character; a few millimetres at the slower ``"nominal"`` pace).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from planner.board import BoardFrame
from planner.bspline import FloatArray
from planner.errors import PlannerError
from planner.feasibility import FeasibilityReport, assess, check
from planner.fit_qp import QpFitter
from planner.limits import VehicleLimits
from planner.minjerk import FitProblem, SplineFit, evaluate_fit, fit_closed_form
from planner.options import PlanOptions
from planner.qp_structure import QpLimits
from planner.refine import (
    Refinement,
    StrokeErrors,
    measure,
    refine,
    stray_error,
    stroke_intervals,
)
from planner.time_law import fly_at_limits
from planner.timing import (
    fit_problem,
    initial_durations,
    point_tolerances_m,
    refine_rebuilder,
    resegment,
)
from planner.trajectory import PlannedTrajectory
from planner.waypoints import KIND_TURNING, WritingPath, build_path

__all__ = [
    "BoardFrame",
    "PlanOptions",
    "PlannedTrajectory",
    "PreparedPlan",
    "VehicleLimits",
    "plan_strokes",
    "prepare",
    "resegment",
]


class _Clock:
    def __init__(self) -> None:
        self.stages: dict[str, float] = {}
        self._t0 = self._last = time.perf_counter()

    def lap(self, name: str) -> None:
        now = time.perf_counter()
        self.stages[name] = self.stages.get(name, 0.0) + (now - self._last) * 1e3
        self._last = now

    def total(self) -> dict[str, float]:
        return {**self.stages, "total": (time.perf_counter() - self._t0) * 1e3}


@dataclass(frozen=True, eq=False)
class PreparedPlan:
    """The data path and the fit problem before re-segmentation (for benchmarks and tools)."""

    path: WritingPath
    """Data points with pen up/down kinds and initial times."""
    problem: FitProblem
    """Fit problem at the initial times (stretched to the limits when the total time is free)."""
    qp_limits: QpLimits
    """Linear limits of the QP."""


def prepare(strokes_board_m: Sequence[FloatArray], options: PlanOptions) -> PreparedPlan:
    """Stages 1-2 of :func:`plan_strokes`: path, initial times and the fit problem."""
    path = build_path(strokes_board_m, options.board, options.path_settings())
    limits = options.qp_limits(path.write_z_m)
    return PreparedPlan(
        path, fit_problem(path, initial_durations(path, options, limits), options), limits
    )


def _within_tolerance(
    path: WritingPath,
    problem: FitProblem,
    fit: SplineFit,
    fitter: QpFitter | None,
    options: PlanOptions,
    limits: QpLimits,
) -> Refinement:
    """Measure the path errors; beyond the tolerance, tighten and re-solve (planner.refine)."""

    def errors_of(prob: FitProblem, f: SplineFit) -> StrokeErrors:
        return measure(
            f.spline, prob, f.residuals_m, path, options.board, options.pen_contact_tolerance_m
        )

    if options.fit_tolerance_m is None:
        return Refinement(problem, fit, errors_of(problem, fit), 0)
    return refine(
        problem,
        fit,
        errors_of,
        fitter.fit if fitter is not None else fit_closed_form,
        refine_rebuilder(options, limits, point_tolerances_m(path, options)),
        tolerance_m=options.fit_tolerance_m,
        fixed_total=options.total_time_s is not None,
        min_duration_s=options.min_segment_time_s,
    )


MAX_INPUT_STROKES = 200
"""Most strokes one job may have (same as the strokes JSON limit)."""
MAX_INPUT_POINTS = 20_000
"""Most input points one job may have, over all strokes (same as the strokes JSON limit)."""
MAX_DATA_POINTS = 3_000
"""Most data points (turning points, approach and lift points) one trajectory is fitted to."""


def _check_size(strokes_board_m: Sequence[FloatArray]) -> None:
    """Refuse oversized input before any heavy work, naming the limit."""
    if len(strokes_board_m) > MAX_INPUT_STROKES:
        raise PlannerError(
            f"{len(strokes_board_m)} strokes; at most {MAX_INPUT_STROKES}", field="strokes"
        )
    total = 0
    for index, stroke in enumerate(strokes_board_m):
        total += int(np.shape(stroke)[0]) if np.ndim(stroke) >= 1 else 0
        if total > MAX_INPUT_POINTS:
            raise PlannerError(
                f"more than {MAX_INPUT_POINTS} points in all", stroke_index=index, field="strokes"
            )


def plan_strokes(strokes_board_m: Sequence[FloatArray], options: PlanOptions) -> PlannedTrajectory:
    """Plan the trajectory writing ``strokes_board_m`` (board-local [m], y up) on ``options.board``.

    Raises :class:`PlannerError` for bad input (naming stroke and point) and
    :class:`InfeasibleTrajectoryError` when the limits cannot be met (naming limit, axis, time)
    or the path cannot be kept within ``fit_tolerance_m`` of the strokes.
    """
    clock = _Clock()
    _check_size(strokes_board_m)
    path = build_path(strokes_board_m, options.board, options.path_settings())
    if path.points_m_enu.shape[0] > MAX_DATA_POINTS:
        raise PlannerError(
            f"{path.points_m_enu.shape[0]} turning points; at most {MAX_DATA_POINTS} can be "
            "written in one job (simplify the drawing)",
            field="strokes",
        )
    clock.lap("path")
    limits = options.qp_limits(path.write_z_m)
    problem = fit_problem(path, initial_durations(path, options, limits), options)
    clock.lap("initial_times")
    fitter = (
        QpFitter(limits, options.solver, dense_budget_s=options.dense_qp_budget_s)
        if options.method == "qp"
        else None
    )
    info: dict[str, float | str] = {}
    if options.resegment:  # its result is the optimal (QP or closed-form) fit at its times
        tolerances = point_tolerances_m(path, options)
        problem, fit, reseg_info = resegment(problem, options, fitter, tolerances)
        info.update(reseg_info)
        clock.lap("resegment")
    else:
        fit = fitter.fit(problem) if fitter is not None else fit_closed_form(problem)
        clock.lap("fit")
    at_limits = options.total_time_s is None and options.pace == "limits"
    flier = fitter if options.time_law and at_limits else None
    flown = None
    if flier is not None:  # a flight within the tolerance needs no refinement of its fit
        flown = _flown_at_limits(path, problem, fit, flier, options)
        clock.lap("time_law")
    if flown is None:
        refined = _within_tolerance(path, problem, fit, fitter, options, limits)
        problem, fit, errors = refined.problem, refined.fit, refined.errors
        info["refine_rounds"] = refined.rounds
        clock.lap("refine")
        report = _assess(path, fit, errors, options)
    else:
        info.update(
            refine_rounds=0, time_law_gain=fit.spline.duration_s / flown[1].spline.duration_s
        )
        problem, fit, errors, report = flown
    check(report)
    if options.fit_tolerance_m is not None and errors.worst_m > options.fit_tolerance_m:
        raise stray_error(problem, limits, errors, options.fit_tolerance_m)
    clock.lap("feasibility")
    return _planned(path, problem, fit, report, clock, info, options)


def _assess(
    path: WritingPath, fit: SplineFit, errors: StrokeErrors, options: PlanOptions
) -> FeasibilityReport:
    turning = path.kinds == KIND_TURNING
    return assess(
        fit.spline,
        options.limits,
        turning_residuals_m=fit.residuals_m[turning],
        turning_stroke_index=path.stroke_of_point[turning],
        n_strokes=len(path.stroke_ranges),
        board_surface_z_m=options.board.surface_z_m,
        path_error_per_stroke_m=errors.path_m,
    )


def _flown_at_limits(
    path: WritingPath,
    problem: FitProblem,
    fit: SplineFit,
    fitter: QpFitter,
    options: PlanOptions,
) -> tuple[FitProblem, SplineFit, StrokeErrors, FeasibilityReport] | None:
    """Stage 5: the fit's path flown on the fastest smooth time law (planner.time_law), measured;
    ``None`` when it is not shorter, strays further than ``fit_tolerance_m`` from the strokes,
    or breaks a limit the time law does not impose (the body rate of eq. 15)."""
    flight = fly_at_limits(fit.spline, fitter.limits, fitter.solve)
    if flight is None:
        return None
    spline = flight.spline
    flown = replace(
        problem,
        times_s=flight.flight_time_s(problem.times_s),
        duration_s=spline.duration_s,
        n_spans=spline.n_spans,
    )
    flown_fit = evaluate_fit(flown, spline.control_points, method=fit.method)
    flown_errors = measure(
        spline, flown, flown_fit.residuals_m, path, options.board, options.pen_contact_tolerance_m
    )
    tolerance_m = options.fit_tolerance_m
    if tolerance_m is not None and flown_errors.worst_m > tolerance_m:
        return None
    report = _assess(path, flown_fit, flown_errors, options)
    if not report.feasible:
        return None
    return flown, flown_fit, flown_errors, report


def _planned(
    path: WritingPath,
    problem: FitProblem,
    fit: SplineFit,
    report: FeasibilityReport,
    clock: _Clock,
    info: dict[str, float | str],
    options: PlanOptions,
) -> PlannedTrajectory:
    times = problem.times_s
    info.update(
        method=fit.method,
        n_spans=problem.n_spans,
        n_data_points=int(times.shape[0]),
        cost=fit.cost,
        jerk_cost=fit.jerk_cost,
        fit_cost=fit.fit_cost,
    )
    return PlannedTrajectory(
        spline=fit.spline,
        feasibility=report,
        timing_ms=clock.total(),
        stroke_intervals_s=stroke_intervals(path, times),
        write_z_m=path.write_z_m,
        pen_contact_tolerance_m=options.pen_contact_tolerance_m,
        turning_points_board_m=path.turning_points_board_m,
        data_points_m_enu=path.points_m_enu,
        data_times_s=times,
        data_kinds=path.kinds,
        limits=options.limits,
        board=options.board,
        info=info,
    )
