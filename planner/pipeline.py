"""Strokes on a board -> one flyable, checked, minimum-jerk trajectory (the Airshow planner).

Stages (each timed in ``PlannedTrajectory.timing_ms``):

1. ``path``: split-and-merge turning points per stroke, pen up/down data path, initial times;
2. ``initial_times``: with a free total time the initial times are stretched until the
   unconstrained (closed-form) fit respects the limits; a fixed total time scales them;
3. ``resegment`` (optional): optimal time re-segmentation (planner.retime);
4. ``fit`` (without re-segmentation): the QP with acceleration, speed and floor limits (or the
   closed form); with re-segmentation its last solve is the final fit;
5. ``refine``: the pen-down path is measured against the strokes; where it strays beyond
   ``fit_tolerance_m`` the fit is tightened locally and solved again (planner.refine);
6. ``feasibility``: report, and :class:`InfeasibleTrajectoryError` if any limit is exceeded or
   the path still strays (naming the limit that pulls it off the strokes, if one does).

Spline size: uniform knots ``knot_spacing_s`` apart (default 0.2 s: 5 control points per second
per axis, finer than the shortest leg time ``min_leg_time_s`` of the path), at least 8 spans.
Jerk weight: ``w_g = jerk_weight_s5`` (default 1e-4 s^5), which keeps turning-point errors to a
few millimetres for 1 m characters at the default limits.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from planner.board import BoardFrame
from planner.bspline import FloatArray
from planner.errors import PlannerError
from planner.feasibility import FeasibilityReport, assess, check
from planner.fit_qp import SPEED_POLYTOPE_APOTHEM, QpFitter, QpLimits
from planner.limits import VehicleLimits
from planner.minjerk import EndState, FitProblem, SplineFit, fit_closed_form
from planner.qp_solvers import SOLVERS
from planner.refine import (
    Refinement,
    StrokeErrors,
    measure,
    refine,
    stray_error,
    stroke_intervals,
)
from planner.retime import SegmentCost, descend_analytic, descend_numerical
from planner.trajectory import PlannedTrajectory
from planner.waypoints import KIND_TURNING, PathSettings, WritingPath, build_path

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

MIN_PLAN_SPANS = 8
QP_PHASE_MAX_ITER = 8
"""Descent iterations on the QP cost (after the closed-form phase); most of the gain comes early."""


def _default_board() -> BoardFrame:
    return BoardFrame(center_m_enu=(0.0, 0.0, 0.0))


@dataclass(frozen=True)
class PlanOptions:
    """Everything ``plan_strokes`` needs besides the strokes. SI units."""

    limits: VehicleLimits = field(default_factory=VehicleLimits)
    """Vehicle limits (acceleration per axis, speed, thrust, body rate)."""
    board: BoardFrame = field(default_factory=_default_board)
    """Board the strokes are written on (strokes are board-local, metres)."""
    write_height_m: float = 0.30
    """Vehicle reference height above the board surface while the brush writes, [m]."""
    clearance_m: float = 0.08
    """Extra height with the pen up, [m] (0: the brush never lifts between strokes)."""
    total_time_s: float | None = None
    """Fixed total duration in [s]; ``None`` lets the re-segmentation choose it (time penalty)."""
    split_threshold_m: float = 0.01
    """Split-and-merge threshold, [m]."""
    resegment: bool = True
    """Run the optimal time re-segmentation."""
    resegment_method: str = "analytic"
    """``"analytic"`` (envelope gradient, L-BFGS) or ``"numerical"`` (the paper's eq. 56)."""
    solver: str = "piqp"
    """QP solver: ``"piqp"`` (default), ``"clarabel"`` or ``"osqp"``."""
    method: str = "qp"
    """``"qp"`` (limits imposed) or ``"closed-form"`` (limits only checked)."""
    sample_rate_hz: float = 100.0
    """Rate of ``TRAJ.json`` samples, [Hz] (>= 100)."""
    knot_spacing_s: float = 0.2
    """Time between spline knots, [s]."""
    jerk_weight_s5: float = 1e-4
    """``w_g`` of eq. (32) in [s^5]."""
    densify_spacing_m: float = 0.05
    """Largest spacing of data points along straight pieces, [m]."""
    time_penalty: float | None = None
    """``rho`` of the free-time cost per second; ``None``: balanced at the initial times."""
    min_segment_time_s: float = 0.05
    """Shortest time re-segmentation may give between two data points, [s]."""
    pen_contact_tolerance_m: float = 0.005
    """Pen counts as down within this height above writing height, [m]."""
    fit_tolerance_m: float | None = 0.025
    """Largest allowed distance of the written path from the strokes (at turning points and
    along the pen-down path), [m]; where the fit strays further it is tightened locally and
    solved again (planner.refine), and only then is the plan refused -- otherwise the limits
    would be met silently by writing a different shape. ``None`` disables the check."""

    def __post_init__(self) -> None:
        if self.solver not in SOLVERS:
            raise PlannerError(f"unknown solver {self.solver!r}; one of {SOLVERS}", field="solver")
        if self.method not in ("qp", "closed-form"):
            raise PlannerError(f"unknown method {self.method!r}", field="method")
        if self.resegment_method not in ("analytic", "numerical"):
            raise PlannerError(f"unknown method {self.resegment_method!r}", field="resegment")
        if self.sample_rate_hz < 100.0:
            raise PlannerError("must be >= 100 Hz", field="sample_rate_hz")
        if self.total_time_s is not None and not self.total_time_s > 0.0:
            raise PlannerError("must be > 0 s", field="total_time_s")
        for name in ("write_height_m", "knot_spacing_s", "jerk_weight_s5", "densify_spacing_m"):
            if not getattr(self, name) > 0.0:
                raise PlannerError(f"must be > 0, got {getattr(self, name)}", field=name)
        if not self.clearance_m >= 0.0:
            raise PlannerError(f"must be >= 0, got {self.clearance_m}", field="clearance_m")

    def path_settings(self) -> PathSettings:
        """Geometry and initial timing of the data path."""
        return PathSettings(
            write_height_m=self.write_height_m,
            clearance_m=self.clearance_m,
            split_threshold_m=self.split_threshold_m,
            densify_spacing_m=self.densify_spacing_m,
            nominal_speed_mps=0.6 * self.limits.v_max_mps,
            nominal_accel_mps2=0.5 * min(self.limits.a_max_mps2),
        )

    def qp_limits(self, write_z_m: float) -> QpLimits:
        """Linear QP limits: acceleration bounds (eq. 13), speed, z never below writing height."""
        lower, upper = self.limits.accel_bounds_mps2()
        return QpLimits(lower, upper, self.limits.v_max_mps, z_floor_m=write_z_m)


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


def _problem(path: WritingPath, durations: FloatArray, options: PlanOptions) -> FitProblem:
    total = float(np.sum(durations))
    n_spans = max(MIN_PLAN_SPANS, math.ceil(total / options.knot_spacing_s))
    times = np.concatenate([[0.0], np.cumsum(durations)])
    return FitProblem(
        times_s=times,
        points_m=path.points_m_enu,
        weights=path.weights,
        n_spans=n_spans,
        duration_s=total,
        jerk_weight_s5=options.jerk_weight_s5,
        start=EndState(path.points_m_enu[0]),
        end=EndState(path.points_m_enu[-1]),
    )


def _limit_ratio(fit: SplineFit, limits: QpLimits) -> float:
    """Time stretch factor that would bring the unconstrained fit within the limits."""
    accel = fit.spline.acceleration_at_knots()
    hi = np.maximum(np.max(accel, axis=0) / np.asarray(limits.accel_upper_mps2), 0.0)
    lo = np.maximum(np.min(accel, axis=0) / np.asarray(limits.accel_lower_mps2), 0.0)
    ratio = math.sqrt(float(max(np.max(hi), np.max(lo))))
    if limits.speed_max_mps is not None:
        t = np.linspace(0.0, fit.spline.duration_s, 4 * fit.spline.n_spans + 1)
        speed = float(np.max(np.linalg.norm(fit.spline.evaluate(t, 1), axis=1)))
        ratio = max(ratio, speed / (limits.speed_max_mps * SPEED_POLYTOPE_APOTHEM))
    return ratio


def _initial_durations(path: WritingPath, options: PlanOptions, limits: QpLimits) -> FloatArray:
    durations = path.segment_durations_s.copy()
    if options.total_time_s is not None:
        return durations * (options.total_time_s / float(np.sum(durations)))
    for _ in range(6):  # free total time: stretch until the unconstrained fit is within limits
        ratio = _limit_ratio(fit_closed_form(_problem(path, durations, options)), limits)
        if ratio <= 1.0:
            break
        durations = durations * (1.05 * ratio)
    return durations


@dataclass(frozen=True)
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
        path, _problem(path, _initial_durations(path, options, limits), options), limits
    )


def _time_penalty(problem: FitProblem, options: PlanOptions) -> float:
    """``rho`` that makes the initial total time stationary under uniform time scaling.

    Scaling all times by ``s`` scales the jerk integral by ``s^-5``; ``d/ds`` at ``s = 1`` of
    ``w_g J_jerk s^-5 + rho s sum T`` vanishes for ``rho = 5 w_g J_jerk / sum T``.
    """
    if options.time_penalty is not None:
        return options.time_penalty
    fit = fit_closed_form(problem)
    rho = 5.0 * problem.jerk_weight_s5 * fit.jerk_cost / problem.duration_s
    return max(rho, 1e-12)


def resegment(
    problem: FitProblem, options: PlanOptions, fitter: QpFitter | None
) -> tuple[FitProblem, SplineFit, dict[str, float]]:
    """Stage 3: optimal time re-segmentation; returns the problem at the new times and its fit.

    Phase A minimises the closed-form cost (cheap, ~0.5 ms per solve). Phase B, only when a
    limit is active at the better of the start and phase A (by the QP cost), continues on the
    QP cost for a few steps. Never worse than the start by the QP cost.
    """
    fixed = options.total_time_s is not None
    rho = 0.0 if fixed else _time_penalty(problem, options)
    descend = descend_analytic if options.resegment_method == "analytic" else descend_numerical
    T0 = problem.segment_durations()
    t_min = options.min_segment_time_s
    phase_a = descend(
        SegmentCost(problem, fixed_total=fixed, time_penalty=rho, min_duration_s=t_min), T0
    )
    info = {"rho": rho, "iterations_closed_form": phase_a.iterations}
    if fitter is None:
        fit = phase_a.fit
        info.update(cost_initial=phase_a.cost_initial, cost_final=phase_a.cost_final)
        return problem.with_durations(phase_a.durations_s), fit, info
    qp_cost = SegmentCost(
        problem, fixed_total=fixed, time_penalty=rho, fitter=fitter, min_duration_s=t_min
    )
    start_fit = qp_cost.fit(T0)
    candidates = [(qp_cost.value(T0, start_fit), T0, start_fit)]
    fit_a = qp_cost.fit(phase_a.durations_s)
    candidates.append((qp_cost.value(phase_a.durations_s, fit_a), phase_a.durations_s, fit_a))
    value, T, best = min(candidates, key=lambda c: c[0])
    if best is None:
        fitter.fit(problem)  # raises the diagnosed InfeasibleTrajectoryError
        raise AssertionError("unreachable")
    fit = best
    iterations_qp = 0
    if fit.active_constraints:
        phase_b = descend(qp_cost, T, max_iter=QP_PHASE_MAX_ITER)
        T, fit, value, iterations_qp = (
            phase_b.durations_s,
            phase_b.fit,
            phase_b.cost_final,
            phase_b.iterations,
        )
    info.update(
        cost_initial=candidates[0][0],
        cost_final=value,
        iterations_qp=iterations_qp,
        qp_solves=fitter.solves,
    )
    return problem.with_durations(T), fit, info


def _rebuild(options: PlanOptions) -> Callable[[FitProblem, FloatArray, FloatArray], FitProblem]:
    """The problem with new weights and durations (spline size following the new total time)."""

    def rebuild(problem: FitProblem, weights: FloatArray, durations: FloatArray) -> FitProblem:
        total = float(np.sum(durations))
        n_spans = max(MIN_PLAN_SPANS, math.ceil(total / options.knot_spacing_s))
        return replace(problem.with_durations(durations), weights=weights, n_spans=n_spans)

    return rebuild


def _within_tolerance(
    path: WritingPath,
    problem: FitProblem,
    fit: SplineFit,
    fitter: QpFitter | None,
    options: PlanOptions,
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
        _rebuild(options),
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
    problem = _problem(path, _initial_durations(path, options, limits), options)
    clock.lap("initial_times")
    fitter = QpFitter(limits, options.solver) if options.method == "qp" else None
    info: dict[str, float | str] = {}
    if options.resegment:  # its result is the optimal (QP or closed-form) fit at its times
        problem, fit, reseg_info = resegment(problem, options, fitter)
        info.update(reseg_info)
        clock.lap("resegment")
    else:
        fit = fitter.fit(problem) if fitter is not None else fit_closed_form(problem)
        clock.lap("fit")
    refined = _within_tolerance(path, problem, fit, fitter, options)
    problem, fit, errors = refined.problem, refined.fit, refined.errors
    info["refine_rounds"] = refined.rounds
    clock.lap("refine")
    turning = path.kinds == KIND_TURNING
    report = assess(
        fit.spline,
        options.limits,
        turning_residuals_m=fit.residuals_m[turning],
        turning_stroke_index=path.stroke_of_point[turning],
        n_strokes=len(path.stroke_ranges),
        board_surface_z_m=options.board.surface_z_m,
        path_error_per_stroke_m=errors.path_m,
    )
    check(report)
    if options.fit_tolerance_m is not None and errors.worst_m > options.fit_tolerance_m:
        raise stray_error(problem, limits, errors, options.fit_tolerance_m)
    clock.lap("feasibility")
    return _planned(path, problem, fit, report, clock, info, options)


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
