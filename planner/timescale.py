"""Time allocation at the limits: every part of the path as fast as its binding limit allows.

With a free total time the planner flies each part of the path as fast as the vehicle limits
allow, keeping the minimum-jerk shape: the data times are re-segmented until the unconstrained
(closed-form, eq. 43) fit touches a limit along the whole path, not only at its worst spot.

Limit usage is read where the limits hold exactly for the whole curve: acceleration at the knots
(exact: it is linear in between) against the per-axis bounds, and the hodograph control points
against the ``v_max`` ball (by the convex hull property the speed then stays within ``v_max``
everywhere; the QP's inscribed polytope, up to 11 % tighter, is only imposed where a hodograph
point leaves the ball, planner.fit_qp). Each is turned into a *time factor*: the uniform stretch
of time that would bring it onto its bound (``sqrt`` of the acceleration share, the speed share
itself). Optionally the fit's distance from each written data point counts too
(``point_tolerance_m``).

1. **Per-segment re-timing** (:meth:`LimitSearch.rebalance`), from the time-optimal times of the
   data polyline: each segment between two data points is stretched or shrunk by the largest
   factor within ``REACH_S`` of it, aiming at ``TARGET`` of the limits
   (stretches overcompensated by ``STRETCH_GAIN``, shrinks damped by ``SHRINK_GAIN``, at most
   ``STEP_MAX`` per round, none below ``min_duration_s``), for at most ``ROUNDS`` rounds.
2. **Global scale** (:meth:`LimitSearch.scale`, a secant on log peak factor against log scale)
   of the round whose total time times peak factor is the least: all times scaled until the
   binding limit is just active (peak in ``[SCALE_LOW, 1]``), mostly in one or two steps.

Why not the paper's gradient re-segmentation with a large time penalty: with the limits active
along the whole path every step needs the QP (100-300 ms per Chinese character instead of a
few ms), and the penalty that makes the limits bind depends on each leg's length. Equalising
the usage of the limits is the time-optimal condition of a path (every part of it at some
limit), reached here with closed-form solves only.

The fit at the result is the unconstrained minimum-jerk fit and respects the limits; the QP
returns it unchanged, or holds it above the floor (planner.floor_qp). Every fit evaluated is a
candidate: the shortest one within the limits is returned (``within_limits`` False only when
none was, the caller's QP then imposes them). Cost: one closed-form solve per step (~0.3 ms for
a Chinese character, its control points and residuals only), 4 to 7 in all.

Measured against TOPP-RA on the plan's own path (benchmarks/bench_planner.py), the minimum-jerk fit
alone flies 1.06-1.19x the time-optimal duration after 10 rounds (median 1.11; 1.15 after the 3 of
``ROUNDS``, planner.time_law then re-times its path, to median 1.07): the cubic spline's
acceleration is piecewise linear between knots 0.2 s apart and passes through zero between an
acceleration and the next braking, where the time-optimal profile switches at once; short strokes,
whose every part lies within a knot spacing of an approach or a lift, lose the most. Even the
fastest cubic spline with knots ``h`` apart, rest to rest (zero end velocity and acceleration),
needs its straight move's bang-coast-bang time plus about ``h`` (an LP over the control points at a
= 0.8 m/s^2, v = 0.5 m/s: 0.2 m in 1.20 s against 1.00, 1 m in 2.83 s against 2.63 at h = 0.2 s;
1.10 s and 2.73 s at h = 0.1 s), and every near-stop of a character (hops, sharp corners) pays part
of it again. At 0.1 s knots the same allocation reaches median 1.10 and worst 1.16, the corpus flown
0.7 % faster in all, for 1.26x the planning time. A lower jerk weight lowers the ratio further only
by sharpening the path, which slows its time-optimal flight more than the plan (at 0.1 s knots and
3e-5 s^5: 1.10 and 1.14, the flights 6.5 % longer). Weighting the fit's error along the path less
than across it does not help alone (corpus and held-out, median / worst: 0.3 at points within 20
degrees of straight 1.113 / 1.197 and 1.116 / 1.166, against 1.112 / 1.185 and 1.112 / 1.186): the
fit drifts back to minimum-jerk timing. At 0.5 within 45 degrees it helps characters of many strokes
(鸟 1.19 -> 1.14) but takes 那 to 1.33, its along-path offsets at turning points read as strays by
planner.refine. The flight's first and last 0.4 s (rest, zero acceleration) cost 0.22-0.25 s per
character, 24 % of ``i``'s gap: finer knots at the ends, not weights, is what the worst characters
need.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np

from planner.bspline import ClampedCubicSpline, FloatArray, apply_band, velocity_values
from planner.errors import PlannerError
from planner.minjerk import FitProblem, SplineFit, closed_form_points, evaluate_fit, fit_closed_form
from planner.qp_structure import SPEED_POLYTOPE_APOTHEM, QpLimits

TARGET = 0.97
"""Share of its binding limit each segment aims at during the per-segment rounds."""
SCALE_LOW = 0.993
"""The global scale stops once the peak time factor is within ``[SCALE_LOW, 1]``."""
SHRINK_GAIN = 0.85
"""Exponent damping the shrink of segments below their limit."""
STRETCH_GAIN = 1.5
"""Exponent of the stretch of segments above their limit (1: taken whole; more settles the
peaks in fewer rounds: on 21 characters of the benchmark's corpus, duration against TOPP-RA's
median 1.105 and worst 1.193 at 1.0 with SHRINK_GAIN 0.7, 1.107 and 1.168 at 1.5 with 0.85)."""
ROUNDS = 3
"""Per-segment rounds at most, each one closed-form solve. Alone (without planner.time_law), on
those 21 characters: 6 rounds, median 1.115 and worst 1.203; 8: 1.107, 1.170; 10: 1.101, 1.160;
12: no better. The time law, which re-times the fit's path afterwards, leaves little to the later
rounds: on ``bench_planner``'s corpus and held-out set (220 characters) the flight's ratio to
TOPP-RA is median 1.068 and worst 1.133 after 10 rounds, 1.069 and 1.138 after 5, 1.072 and 1.136
after 3; 3 against 10 spare a plan 6 or 7 closed-form solves (about 0.3 ms each)."""
REACH_S = 0.2
"""A segment's factor is the largest of the samples within about this time of it, [s] (in whole
knot spacings, at least one): a segment counts as at its limit when a limit is reached this
close to it (the acceleration of these fits swings between its bounds over about that time). A
time, not a number of knot spacings: on 21 characters of the benchmark's corpus at 0.1 s knots,
duration against TOPP-RA's median and worst 1.102 and 1.210 at one knot spacing, 1.101 and
1.156 at two (0.2 s); at the 0.2 s knots it was set at, one spacing (0.75, 1.25, 1.5 spacings:
worst 1.212, 1.191, 1.190 against 1.186)."""
STEP_MAX = 2.0
"""Largest stretch (and inverse of the largest shrink) of a segment in one round."""
ROUND_TOLERANCE = 0.03
"""Rounds stop once every segment factor is within this of ``TARGET``."""
FIXED_SPANS_LOG_RANGE = 0.15
"""The global scale keeps the spline size while ``|log scale|`` stays within this (~16 %)."""
SCALE_LOG_STEP_MAX = math.log(STEP_MAX)
"""Largest change of the log scale in one secant step (a peak that barely answers a scale, a
point tolerance factor of 0.2 mm, once drove a plan to 1e11 s along the secant's flattest
slope)."""
SCALE_STEPS = 6
"""Secant steps of each global scale at most."""


@dataclass(frozen=True, eq=False)
class Allocation:
    """An allocation of segment durations and its fit (see :class:`LimitSearch`)."""

    durations_s: FloatArray
    """Segment durations ``T_i`` [s]."""
    problem: FitProblem
    """The fit problem at those durations."""
    control_points: FloatArray
    """Control points (n_ctrl, 3) of its closed-form (minimum-jerk) fit."""
    peak_factor: float
    """Largest time factor of the fit (<= 1: within the QP's limits)."""
    solves: int
    """Closed-form solves spent."""

    @property
    def within_limits(self) -> bool:
        """True when the closed-form fit respects every QP limit."""
        return self.peak_factor <= 1.0

    @cached_property
    def fit(self) -> SplineFit:
        """The closed-form fit with its costs (computed on demand: the search needs only its
        control points and residuals)."""
        return evaluate_fit(self.problem, self.control_points)


def time_factors(spline: ClampedCubicSpline, limits: QpLimits) -> tuple[FloatArray, FloatArray]:
    """(time [s], time factor) of every limited quantity of ``spline`` (see module docstring)."""
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
    factor_v = np.linalg.norm(hodograph, axis=1) / limits.speed_max_mps
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

    def evaluate(
        self, durations_s: FloatArray, n_spans: int | None = None
    ) -> tuple[Allocation, FloatArray, FloatArray]:
        """The closed-form fit at ``durations_s`` (raised to the shortest durations) and its
        time factors (times, factors); ``n_spans`` keeps the spline size (default: as
        ``make_problem`` sizes it)."""
        durations_s = np.maximum(durations_s, self.min_duration_s)
        problem = self.make_problem(durations_s)
        if n_spans is not None and n_spans != problem.n_spans:
            problem = replace(problem, n_spans=n_spans)
        tau, residuals_m = closed_form_points(problem)
        self.solves += 1
        spline = ClampedCubicSpline(control_points=tau, duration_s=problem.duration_s)
        t, f = time_factors(spline, self.limits)
        if self.point_tolerance_m is not None:
            residual = np.sqrt(np.sum(residuals_m * residuals_m, axis=1)) / self.point_tolerance_m
            t = np.concatenate([t, problem.times_s])
            f = np.concatenate([f, np.sqrt(residual)])
        found = Allocation(durations_s, problem, tau, float(np.max(f)), self.solves)
        self._last = found
        if found.within_limits and (
            self._best is None or problem.duration_s < self._best.problem.duration_s
        ):
            self._best = found
        return found, t, f

    def scale(self, durations_s: FloatArray, known: Allocation | None = None) -> FloatArray:
        """Global scale: secant on (log scale, log peak) until the peak is in ``[SCALE_LOW, 1]``
        (first step with slope -1: a factor is inversely proportional to a uniform scale);
        ``known``: the allocation at ``durations_s`` when it was evaluated already.

        Within ``FIXED_SPANS_LOG_RANGE`` the spline keeps the size it has at ``durations_s``:
        with the same knots in the scaled time, the fit keeps its shape but for the jerk weight's
        share (``alpha^5``, felt most near the rest ends), so the peak follows ``1 / scale``
        closely and one or two steps mostly land in the interval. (Knots that follow the total
        time move against the data: at 24 s a 1 % scale changed the peak by +0.3 % instead of
        -1 %, and the secant then overshot by 8 %.)
        Beyond it the size follows the total time: a fit that strays from its points (a point
        tolerance factor) comes closer to them with more knots, not with the same ones slower."""
        T = np.asarray(durations_s, dtype=np.float64)
        goal = math.log(0.5 * (1.0 + SCALE_LOW))
        log_scale, seen = 0.0, []
        n_spans = None if known is None else known.problem.n_spans
        for _ in range(SCALE_STEPS):
            if known is None:
                fixed = n_spans if abs(log_scale) <= FIXED_SPANS_LOG_RANGE else None
                found, _, _ = self.evaluate(T * math.exp(log_scale), fixed)
            else:
                found, known = known, None
            n_spans = n_spans or found.problem.n_spans
            if SCALE_LOW <= found.peak_factor <= 1.0 or found.peak_factor <= 0.0:
                break
            seen.append((log_scale, math.log(found.peak_factor)))
            slope = -1.0
            if len(seen) >= 2 and seen[-1][0] != seen[-2][0]:
                slope = (seen[-1][1] - seen[-2][1]) / (seen[-1][0] - seen[-2][0])
                slope = min(max(slope, -3.0), -0.2)
            step = (goal - seen[-1][1]) / slope
            log_scale += min(max(step, -SCALE_LOG_STEP_MAX), SCALE_LOG_STEP_MAX)
        return np.maximum(T * math.exp(log_scale), self.min_duration_s)

    def rebalance(self, durations_s: FloatArray) -> FloatArray:
        """Per-segment rounds towards ``TARGET`` of the limits, then the global scale of the
        round whose scaled total (total time x peak factor) is the shortest: a late round that
        raised a peak somewhere does not slow the whole plan down. (Stopping after two rounds in
        a row that brought nothing saved 11 % of the solves but raised the worst of the corpus
        from 1.167 to 1.216x TOPP-RA: a round may still improve after two that did not.)"""
        T = np.asarray(durations_s, dtype=np.float64)
        best: Allocation | None = None
        for _ in range(ROUNDS):
            found, t, f = self.evaluate(T)
            if best is None or _scaled_total(found) < _scaled_total(best):
                best = found
            F = segment_factors(found.problem.times_s, t, f, _reach_s(found.problem)) / TARGET
            if float(np.max(np.abs(F - 1.0))) < ROUND_TOLERANCE:
                break
            gain = np.where(F > 1.0, STRETCH_GAIN, SHRINK_GAIN)
            step = np.clip(np.power(F, gain), 1 / STEP_MAX, STEP_MAX)
            T = np.maximum(found.durations_s * step, self.min_duration_s)
        assert best is not None
        return self.scale(best.durations_s, best)

    def result(self) -> Allocation:
        """The shortest allocation within the limits (the last one if none was)."""
        found = self._best if self._best is not None else self._last
        if found is None:
            raise PlannerError("no allocation was evaluated", field="durations")
        return replace(found, solves=self.solves)


def _reach_s(problem: FitProblem) -> float:
    """``REACH_S`` rounded to whole knot spacings of ``problem`` (at least one), [s]: one at the
    default 0.2 s knots, as the rounds were measured (a plan's spacing, its total time over its
    spans, lies a little under the option's)."""
    spacing_s = problem.duration_s / problem.n_spans
    return max(1, round(REACH_S / spacing_s)) * spacing_s


def _scaled_total(found: Allocation) -> float:
    """Total time [s] of ``found`` scaled until its peak is at its bound (factor ~ 1 / scale)."""
    return found.problem.duration_s * max(found.peak_factor, 1e-9)


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
