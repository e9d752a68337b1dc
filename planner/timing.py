"""Time allocation of the Airshow planner: the initial times and the time re-segmentation.

With a fixed total time the nominal leg times of the path (planner.waypoints) are scaled to it
and the paper's optimal time re-segmentation (section 5.4, planner.retime) redistributes them
at that total (cost: jerk + fit).

With a free total time (``PlanOptions.pace``):

- ``"limits"`` (default): time-optimal in pace, minimum-jerk in shape. Initial times: the
  time-optimal bang-bang times along the data polyline (planner.polyline_timing); without
  re-segmentation they are scaled until the binding limit of the closed-form fit is just active
  (a secant on one global scale). Re-segmentation: per-segment re-timing from them until every
  part of the path flies at its binding limit, then that scale (planner.timescale). The fit
  stays the unconstrained minimum-jerk fit (the QP only confirms it, or holds it above the
  floor); measured against TOPP-RA on the same path, durations are 1.06-1.17x optimal.
- ``"nominal"`` (the default before issue 15): each leg at 0.6 v_max and half the smallest
  acceleration limit, stretched where the fit breaks a limit; then the paper's free-time
  re-segmentation with a time penalty that makes that total stationary (1.5-2x optimal).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from planner.bspline import FloatArray
from planner.fit_qp import QpFitter
from planner.minjerk import EndState, FitProblem, SplineFit, fit_closed_form
from planner.options import PlanOptions
from planner.polyline_timing import polyline_durations_s
from planner.qp_structure import QpLimits
from planner.timescale import Allocation, LimitSearch, stationary_time_penalty, stretch_nominal
from planner.waypoints import KIND_DENSE, KIND_HOP, KIND_TURNING, WritingPath

MIN_PLAN_SPANS = 8
"""Fewest knot spans of a trajectory."""
FIDELITY_SHARE = 0.8
"""At pace ``"limits"`` the re-timing also keeps the fit within this share of
``fit_tolerance_m`` of every written data point (slower where a corner would be cut)."""
QP_PHASE_MAX_ITER = 8
"""Descent iterations on the QP cost (after the closed-form phase); most of the gain comes early."""


def fit_problem(path: WritingPath, durations: FloatArray, options: PlanOptions) -> FitProblem:
    """The rest-to-rest fit problem of ``path`` with segment ``durations`` [s]."""
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


def initial_durations(path: WritingPath, options: PlanOptions, limits: QpLimits) -> FloatArray:
    """Stage 2 of plan_strokes (see the module docstring)."""
    durations = path.segment_durations_s.copy()
    if options.total_time_s is not None:
        return durations * (options.total_time_s / float(np.sum(durations)))
    if options.pace == "limits":
        durations = polyline_durations_s(
            path.points_m_enu,
            limits,
            corner_time_s=options.knot_spacing_s,
            min_duration_s=options.min_segment_time_s,
        )
        if options.resegment:  # its per-segment rounds start from the polyline times
            return durations
        return _limit_search(path, options, limits).scale(durations)
    return stretch_nominal(_maker(path, options), durations, limits)


def _maker(path: WritingPath, options: PlanOptions) -> Callable[[FloatArray], FitProblem]:
    return lambda durations: fit_problem(path, durations, options)


def _limit_search(path: WritingPath, options: PlanOptions, limits: QpLimits) -> LimitSearch:
    return LimitSearch(
        _maker(path, options),
        limits,
        min_duration_s=options.min_segment_time_s,
        point_tolerance_m=point_tolerances_m(path, options),
    )


def point_tolerances_m(path: WritingPath, options: PlanOptions) -> FloatArray | None:
    """Per data point: how far the fit may pass from it while re-timing at the limits [m]:
    ``FIDELITY_SHARE`` of the fit tolerance for the points the brush writes or hops on, any
    distance for the pen-up ones (None without a fit tolerance)."""
    if options.fit_tolerance_m is None or FIDELITY_SHARE <= 0.0:
        return None
    written = np.isin(path.kinds, (KIND_TURNING, KIND_DENSE, KIND_HOP))
    return np.where(written, FIDELITY_SHARE * options.fit_tolerance_m, np.inf)


def _time_penalty(problem: FitProblem, options: PlanOptions) -> float:
    """``rho`` that makes the initial total time stationary under uniform time scaling.

    Scaling all times by ``s`` scales the jerk integral by ``s^-5``; ``d/ds`` at ``s = 1`` of
    ``w_g J_jerk s^-5 + rho s sum T`` vanishes for ``rho = 5 w_g J_jerk / sum T``.
    """
    if options.time_penalty is not None:
        return options.time_penalty
    return stationary_time_penalty(fit_closed_form(problem), problem)


def resegment(
    problem: FitProblem,
    options: PlanOptions,
    fitter: QpFitter | None,
    point_tolerance_m: FloatArray | None = None,
) -> tuple[FitProblem, SplineFit, dict[str, float]]:
    """Stage 3: optimal time re-segmentation; returns the problem at the new times and its fit.

    Phase A minimises the closed-form cost (cheap, ~0.5 ms per solve). Phase B, only when a
    limit is active at the better of the start and phase A (by the QP cost), continues on the
    QP cost for a few steps. Never worse than the start by the QP cost.

    With a free total time at pace ``"limits"`` it is the per-segment re-timing of
    planner.timescale instead (the QP then only confirms the closed-form fit, or clips it),
    keeping the fit within ``point_tolerance_m`` of the data points (:func:`point_tolerances_m`).
    """
    if options.total_time_s is None and options.pace == "limits":
        return _resegment_at_limits(problem, options, fitter, point_tolerance_m)
    return _resegment_paper(problem, options, fitter)


def _resegment_paper(
    problem: FitProblem, options: PlanOptions, fitter: QpFitter | None
) -> tuple[FitProblem, SplineFit, dict[str, float]]:
    # imported here: the default pace never runs the paper's method (nor its L-BFGS)
    from planner.retime import SegmentCost, descend_analytic, descend_numerical

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


def _resegment_at_limits(
    problem: FitProblem,
    options: PlanOptions,
    fitter: QpFitter | None,
    point_tolerance_m: FloatArray | None,
) -> tuple[FitProblem, SplineFit, dict[str, float]]:
    limits = fitter.limits if fitter is not None else options.qp_limits(problem.points_m[0, 2])
    found = allocate(
        problem, problem.weights, problem.segment_durations(), options, limits, point_tolerance_m
    )
    fit = fitter.fit(found.problem) if fitter is not None else found.fit
    info = {"peak_time_factor": found.peak_factor, "closed_form_solves": float(found.solves)}
    if fitter is not None:
        info["qp_solves"] = float(fitter.solves)
    return found.problem, fit, info


def allocate(
    problem: FitProblem,
    weights: FloatArray,
    durations_s: FloatArray,
    options: PlanOptions,
    limits: QpLimits,
    point_tolerance_m: FloatArray | None,
    floor_s: FloatArray | None = None,
) -> Allocation:
    """Per-segment re-timing at the limits (planner.timescale) of ``problem`` with ``weights``,
    starting from ``durations_s``, no segment shorter than ``floor_s`` (default: the options'
    shortest segment time)."""
    rebuild = rebuilder(options)
    search = LimitSearch(
        lambda durations: rebuild(problem, weights, durations),
        limits,
        min_duration_s=options.min_segment_time_s if floor_s is None else floor_s,
        point_tolerance_m=point_tolerance_m,
    )
    search.rebalance(durations_s)
    return search.result()


def rebuilder(options: PlanOptions) -> Callable[[FitProblem, FloatArray, FloatArray], FitProblem]:
    """The problem with new weights and durations (spline size following the new total time)."""

    def rebuild(problem: FitProblem, weights: FloatArray, durations: FloatArray) -> FitProblem:
        total = float(np.sum(durations))
        n_spans = max(MIN_PLAN_SPANS, math.ceil(total / options.knot_spacing_s))
        return replace(problem.with_durations(durations), weights=weights, n_spans=n_spans)

    return rebuild


def refine_rebuilder(
    options: PlanOptions, limits: QpLimits, point_tolerance_m: FloatArray | None
) -> Callable[[FitProblem, FloatArray, FloatArray], FitProblem]:
    """How planner.refine builds its next problem from new weights and durations.

    At pace ``"limits"`` (free total time) the tightened problem is re-timed at the limits from
    the current times, so that the limits hold by time rather than by deforming the path; the
    segments stretched around a stray keep at least their stretched time (the re-timing would
    otherwise shrink them back).
    """
    plain = rebuilder(options)
    if options.total_time_s is not None or options.pace != "limits":
        return plain

    def rebuild(problem: FitProblem, weights: FloatArray, durations: FloatArray) -> FitProblem:
        current = problem.segment_durations()
        floor = np.where(durations > current, durations, options.min_segment_time_s)
        found = allocate(problem, weights, current, options, limits, point_tolerance_m, floor)
        return found.problem

    return rebuild
