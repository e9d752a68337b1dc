"""Time allocation at the limits: every part of the path as fast as its binding limit allows.

With a free total time the planner flies each part of the path as fast as the vehicle limits
allow, keeping the minimum-jerk shape: the data times are re-segmented until the unconstrained
(closed-form, eq. 43) fit touches a limit along the whole path, not only at its worst spot.

Limit usage is read where the QP imposes the limits (planner.qp_structure): acceleration at the
knots (exact: it is linear in between) against the per-axis bounds, and the hodograph control
points against the speed polytope. Each is turned into a *time factor*: the uniform stretch of time
that would bring it onto its bound (``sqrt`` of the acceleration share, the speed share itself).
Optionally the fit's distance from each written data point counts too (``point_tolerance_m``).

1. **Global scale** (:meth:`LimitSearch.scale`, a secant on log peak factor against log scale):
   all times scaled until the binding limit is just active (peak in ``[SCALE_LOW, 1]``).
2. **Per-segment re-timing** (:meth:`LimitSearch.rebalance`): each segment between two data
   points is stretched or shrunk by the largest factor within ``REACH_SPANS`` knot spacings of
   it, aiming at ``TARGET`` of the limits (stretches taken whole, shrinks damped by
   ``SHRINK_GAIN``, at most ``STEP_MAX`` per round, none below ``min_duration_s``), for at most
   ``ROUNDS`` rounds; then the global scale again, so that the peak is just at its bound.

Why not the paper's gradient re-segmentation with a large time penalty: with the limits active
along the whole path every step needs the QP (100-300 ms per Chinese character instead of a
few ms), and the penalty that makes the limits bind depends on each leg's length. Equalising
the usage of the limits is the time-optimal condition of a path (every part of it at some
limit), reached here with closed-form solves only.

The fit at the result is the unconstrained minimum-jerk fit and respects the QP's limits, so the
QP returns it unchanged. Every fit evaluated is a candidate: the shortest one within the limits
is returned (``within_limits`` False only when none was, the caller's QP then imposes them).
Cost: one closed-form solve per step (~0.5 ms for a Chinese character), about 15 in all.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from planner.bspline import FloatArray, apply_band, velocity_values
from planner.errors import PlannerError
from planner.minjerk import FitProblem, SplineFit, fit_closed_form
from planner.qp_structure import SPEED_DIRECTIONS, SPEED_POLYTOPE_APOTHEM, QpLimits

TARGET = 0.97
"""Share of its binding limit each segment aims at during the per-segment rounds."""
SCALE_LOW = 0.985
"""The global scale stops once the peak time factor is within ``[SCALE_LOW, 1]``."""
SHRINK_GAIN = 0.7
"""Exponent damping the shrink of segments below their limit."""
STRETCH_GAIN = 1.0
"""Exponent of the stretch of segments above their limit (1: taken whole)."""
ROUNDS = 8
"""Per-segment rounds at most."""
REACH_SPANS = 1.0
"""A segment's factor is the largest of the samples within this many knot spacings of it."""
STEP_MAX = 2.0
"""Largest stretch (and inverse of the largest shrink) of a segment in one round."""
ROUND_TOLERANCE = 0.03
"""Rounds stop once every segment factor is within this of ``TARGET``."""
SCALE_STEPS = 6
"""Secant steps of each global scale at most."""


@dataclass(frozen=True)
class Allocation:
    """An allocation of segment durations and its fit (see :class:`LimitSearch`)."""

    durations_s: FloatArray
    """Segment durations ``T_i`` [s]."""
    problem: FitProblem
    """The fit problem at those durations."""
    fit: SplineFit
    """Its closed-form (minimum-jerk) fit."""
    peak_factor: float
    """Largest time factor of the fit (<= 1: within the QP's limits)."""
    solves: int
    """Closed-form solves spent."""

    @property
    def within_limits(self) -> bool:
        """True when the closed-form fit respects every QP limit."""
        return self.peak_factor <= 1.0


def time_factors(fit: SplineFit, limits: QpLimits) -> tuple[FloatArray, FloatArray]:
    """(time [s], time factor) of every limited quantity of ``fit`` (see module docstring)."""
    spline = fit.spline
    alpha = spline.alpha
    m = spline.n_spans
    accel = spline.acceleration_at_knots()
    share = np.maximum(
        accel / np.asarray(limits.accel_upper_mps2), accel / np.asarray(limits.accel_lower_mps2)
    )
    factor_a = np.sqrt(np.maximum(np.max(share, axis=1), 0.0))
    t_a = np.arange(m + 1) / alpha
    if limits.speed_max_mps is None:
        return t_a, factor_a
    hodograph = apply_band(velocity_values(m), spline.control_points) * alpha  # (m + 2, 3)
    bound = limits.speed_max_mps * SPEED_POLYTOPE_APOTHEM
    factor_v = np.max(np.abs(hodograph @ SPEED_DIRECTIONS.T), axis=1) / bound
    t_v = np.clip(np.arange(m + 2) - 0.5, 0.0, m) / alpha  # where each hodograph point acts
    return np.concatenate([t_a, t_v]), np.concatenate([factor_a, factor_v])


def segment_factors(
    data_times_s: FloatArray, sample_t_s: FloatArray, sample_factor: FloatArray, reach_s: float
) -> FloatArray:
    """Per data segment: the largest factor of the samples within ``reach_s`` of it."""
    order = np.argsort(sample_t_s, kind="stable")
    t = sample_t_s[order]
    f = np.append(sample_factor[order], 0.0)
    lo = np.searchsorted(t, data_times_s[:-1] - reach_s, side="left")
    hi = np.maximum(np.searchsorted(t, data_times_s[1:] + reach_s, side="right"), lo + 1)
    idx = np.column_stack([np.minimum(lo, t.shape[0] - 1), np.minimum(hi, t.shape[0])]).ravel()
    return np.asarray(np.maximum.reduceat(f, idx)[::2])


class LimitSearch:
    """Evaluates allocations and keeps the shortest one within the limits.

    ``make_problem(durations)`` builds the fit problem (spline size following the total time).
    With ``point_tolerance_m`` the fit's distance from each data point counts as one more limit:
    its time factor is ``sqrt(distance / tolerance)`` (a fit cutting a corner at speed strays
    roughly in proportion to the speed or its square: slower, it keeps to the points).
    """

    def __init__(
        self,
        make_problem: Callable[[FloatArray], FitProblem],
        limits: QpLimits,
        *,
        min_duration_s: float | FloatArray,
        point_tolerance_m: FloatArray | None = None,
    ) -> None:
        self.make_problem = make_problem
        self.limits = limits
        self.min_duration_s = min_duration_s
        """Shortest duration [s] of every segment (or of each segment, an array)."""
        self.point_tolerance_m = point_tolerance_m
        """Per data point: largest distance of the fit from it [m] (``inf``: any), or None."""
        self.solves = 0
        self._best: Allocation | None = None
        self._last: Allocation | None = None

    def evaluate(self, durations_s: FloatArray) -> tuple[Allocation, FloatArray, FloatArray]:
        """The closed-form fit at ``durations_s`` (raised to the shortest durations) and its
        time factors (times, factors)."""
        durations_s = np.maximum(durations_s, self.min_duration_s)
        problem = self.make_problem(durations_s)
        fit = fit_closed_form(problem)
        self.solves += 1
        t, f = time_factors(fit, self.limits)
        if self.point_tolerance_m is not None:
            residual = np.linalg.norm(fit.residuals_m, axis=1) / self.point_tolerance_m
            t = np.concatenate([t, problem.times_s])
            f = np.concatenate([f, np.sqrt(residual)])
        found = Allocation(durations_s, problem, fit, float(np.max(f)), self.solves)
        self._last = found
        if found.within_limits and (
            self._best is None or problem.duration_s < self._best.problem.duration_s
        ):
            self._best = found
        return found, t, f

    def scale(self, durations_s: FloatArray) -> FloatArray:
        """Global scale: secant on (log scale, log peak) until the peak is in ``[SCALE_LOW, 1]``
        (first step with slope -1: a factor is inversely proportional to a uniform scale)."""
        T = np.asarray(durations_s, dtype=np.float64)
        goal = math.log(0.5 * (1.0 + SCALE_LOW))
        log_scale, seen = 0.0, []
        for _ in range(SCALE_STEPS):
            found, _, _ = self.evaluate(T * math.exp(log_scale))
            if SCALE_LOW <= found.peak_factor <= 1.0 or found.peak_factor <= 0.0:
                break
            seen.append((log_scale, math.log(found.peak_factor)))
            slope = -1.0
            if len(seen) >= 2 and seen[-1][0] != seen[-2][0]:
                slope = (seen[-1][1] - seen[-2][1]) / (seen[-1][0] - seen[-2][0])
                slope = min(max(slope, -3.0), -0.2)
            log_scale += (goal - seen[-1][1]) / slope
        return np.maximum(T * math.exp(log_scale), self.min_duration_s)

    def rebalance(self, durations_s: FloatArray) -> FloatArray:
        """Per-segment rounds towards ``TARGET`` of the limits, then the global scale again."""
        T = np.asarray(durations_s, dtype=np.float64)
        for _ in range(ROUNDS):
            found, t, f = self.evaluate(T)
            problem = found.problem
            reach = REACH_SPANS * problem.duration_s / problem.n_spans
            F = segment_factors(problem.times_s, t, f, reach) / TARGET
            if float(np.max(np.abs(F - 1.0))) < ROUND_TOLERANCE:
                break
            gain = np.where(F > 1.0, STRETCH_GAIN, SHRINK_GAIN)
            step = np.clip(np.power(F, gain), 1 / STEP_MAX, STEP_MAX)
            T = np.maximum(T * step, self.min_duration_s)
        return self.scale(T)

    def result(self) -> Allocation:
        """The shortest allocation within the limits (the last one if none was)."""
        found = self._best if self._best is not None else self._last
        if found is None:
            raise PlannerError("no allocation was evaluated", field="durations")
        return replace(found, solves=self.solves)


def stationary_time_penalty(fit: SplineFit, problem: FitProblem) -> float:
    """``rho`` that makes ``problem``'s total time stationary under uniform time scaling.

    Scaling all times by ``s`` scales the jerk integral by ``s^-5``; ``d/ds`` at ``s = 1`` of
    ``w_g J_jerk s^-5 + rho s sum T`` vanishes for ``rho = 5 w_g J_jerk / sum T``.
    """
    return max(5.0 * problem.jerk_weight_s5 * fit.jerk_cost / problem.duration_s, 1e-12)


def _nominal_ratio(fit: SplineFit, limits: QpLimits) -> float:
    """Time stretch factor that would bring the unconstrained fit within the limits (acceleration
    at the knots, speed sampled along the curve against the polytope's apothem)."""
    accel = fit.spline.acceleration_at_knots()
    hi = np.maximum(np.max(accel, axis=0) / np.asarray(limits.accel_upper_mps2), 0.0)
    lo = np.maximum(np.min(accel, axis=0) / np.asarray(limits.accel_lower_mps2), 0.0)
    ratio = float(np.sqrt(max(np.max(hi), np.max(lo))))
    if limits.speed_max_mps is not None:
        spline = fit.spline
        t = np.linspace(0.0, spline.duration_s, 4 * spline.n_spans + 1)
        speed = float(np.max(np.linalg.norm(spline.evaluate(t, 1), axis=1)))
        ratio = max(ratio, speed / (limits.speed_max_mps * SPEED_POLYTOPE_APOTHEM))
    return ratio


def stretch_nominal(
    make_problem: Callable[[FloatArray], FitProblem], durations_s: FloatArray, limits: QpLimits
) -> FloatArray:
    """The ``"nominal"`` pace: the nominal durations, stretched (never shrunk) until the
    unconstrained fit is within the limits."""
    T = np.array(durations_s, dtype=np.float64)
    for _ in range(6):
        ratio = _nominal_ratio(fit_closed_form(make_problem(T)), limits)
        if ratio <= 1.0:
            break
        T = T * (1.05 * ratio)
    return T


__all__ = [
    "Allocation",
    "LimitSearch",
    "segment_factors",
    "stationary_time_penalty",
    "stretch_nominal",
    "time_factors",
]
