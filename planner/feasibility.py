"""Feasibility report of a planned spline: limits, thrust (eq. 12-14), body rate (eq. 15), fit.

Peaks are exact where the spline structure allows it: acceleration is piecewise linear (extremes
at knots), jerk piecewise constant, thrust ``m ||a - g||`` convex in ``a`` (maximum at knots).
Speed is a quartic per span and is sampled at ``SAMPLED_RATE_HZ`` (every span, both ends
included), at least ``PEAK_SAMPLES_PER_SPAN`` times per span (relative error < 1e-4), as is the
height above the board; the acceleration is read at the knots, which bound its samples. The
largest share of the bounds of those samples is reported and checked: the limits hold densely,
not only where the QP imposes them (the hodograph control points are kept in the ``v_max``
ball, which bounds the speed everywhere; acceleration bounds are exact).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from planner.bspline import ClampedCubicSpline, FloatArray, IntArray, span_coefficients
from planner.errors import InfeasibleTrajectoryError
from planner.limits import GRAVITY_MPS2, VehicleLimits

AXES = ("x", "y", "z")
RELATIVE_TOLERANCE = 1e-6
"""Slack allowed over a limit for solver round-off (relative to the bound)."""
SAMPLED_RATE_HZ = 1000.0
"""Rate of the dense check of the acceleration and speed limits, [Hz]."""
PEAK_SAMPLES_PER_SPAN = 33
"""Fewest samples per span of the peak speed and the lowest height (relative error of the peak
speed < 1e-4; more where the dense check samples faster)."""

_GRAVITY = np.array([0.0, 0.0, -GRAVITY_MPS2])


@dataclass(frozen=True)
class FeasibilityReport:
    """What the planned reference asks of the vehicle, against its limits. SI units, ENU."""

    peak_accel_mps2: tuple[float, float, float]
    """Largest |acceleration| per axis x, y, z in [m/s^2]."""
    peak_accel_time_s: tuple[float, float, float]
    """Time of each of those peaks in [s]."""
    accel_min_mps2: tuple[float, float, float]
    """Most negative acceleration per axis in [m/s^2]."""
    accel_max_mps2: tuple[float, float, float]
    """Most positive acceleration per axis in [m/s^2]."""
    accel_lower_mps2: tuple[float, float, float]
    """Lower acceleration bound per axis in [m/s^2] (a_max combined with eq. 13)."""
    accel_upper_mps2: tuple[float, float, float]
    """Upper acceleration bound per axis in [m/s^2]."""
    peak_speed_mps: float
    """Largest speed ||v|| in [m/s]."""
    peak_speed_time_s: float
    """Time of the largest speed in [s]."""
    v_max_mps: float
    """Speed limit in [m/s]."""
    peak_thrust_n: float
    """Largest collective thrust ``m ||a - g||`` (eq. 12) in [N]."""
    min_thrust_n: float
    """Smallest collective thrust in [N]."""
    thrust_max_n: float
    """Thrust limit in [N]."""
    thrust_split_mps2: tuple[float, float, float]
    """Per-axis allowance alpha_i of eq. (13)-(14) in [m/s^2]."""
    peak_jerk_mps3: tuple[float, float, float]
    """Largest |jerk| per axis in [m/s^3]."""
    body_rate_bound_radps: float
    """Upper bound of the body-rate norm, eq. (15), in [rad/s]."""
    body_rate_max_radps: float
    """Allowed body-rate bound in [rad/s]."""
    fit_error_max_m: float
    """Largest distance between the path and a turning point at its time, in [m]."""
    fit_error_rms_m: float
    """RMS of those distances in [m]."""
    fit_error_max_per_stroke_m: tuple[float, ...]
    """Largest turning-point distance of each stroke in [m]."""
    min_height_above_board_m: float
    """Lowest height of the reference above the board surface in [m]."""
    path_error_max_per_stroke_m: tuple[float, ...] = ()
    """Per stroke: largest horizontal distance of the pen-down path from the polyline through
    its turning points, in [m] (what the brush actually draws, not only at the data times)."""
    sampled_rate_hz: float = 0.0
    """Rate the reference was also sampled at to check acceleration and speed, [Hz] (0: not)."""
    sampled_accel_share: float = 0.0
    """Largest ``a_i / upper_i`` or ``a_i / lower_i`` over those samples (<= 1: within)."""
    sampled_speed_share: float = 0.0
    """Largest ``||v|| / v_max`` over those samples (<= 1: within)."""

    @property
    def path_error_max_m(self) -> float:
        """Largest pen-down distance from the stroke polylines over all strokes, [m]."""
        return max(self.path_error_max_per_stroke_m, default=0.0)

    @property
    def feasible(self) -> bool:
        """True when no limit is exceeded (beyond round-off)."""
        return not self.violations()

    def violations(self) -> list[InfeasibleTrajectoryError]:
        """Every exceeded limit, worst first within each kind."""
        return list(_violations(self))

    def to_json_dict(self) -> dict[str, Any]:
        """Plain JSON-able dictionary (tuples become lists), plus ``feasible``."""
        data = {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}
        data["feasible"] = self.feasible
        data["path_error_max_m"] = self.path_error_max_m
        return data


def _over(value: float, bound: float) -> bool:
    return value > bound + RELATIVE_TOLERANCE * abs(bound) + 1e-9


def _violations(r: FeasibilityReport) -> list[InfeasibleTrajectoryError]:
    found = []
    for i, axis in enumerate(AXES):
        hi, lo = r.accel_upper_mps2[i], r.accel_lower_mps2[i]
        if _over(r.accel_max_mps2[i], hi) or _over(-r.accel_min_mps2[i], -lo):
            value = (
                r.accel_max_mps2[i]
                if r.accel_max_mps2[i] - hi > lo - r.accel_min_mps2[i]
                else (r.accel_min_mps2[i])
            )
            bound = hi if value > 0 else lo
            found.append(
                InfeasibleTrajectoryError(
                    f"acceleration limit: a_{axis} reaches {value:+.3f} m/s^2 at"
                    f" t={r.peak_accel_time_s[i]:.2f} s (bound {bound:+.3f} m/s^2)",
                    limit="a_max",
                    axis=axis,
                    t_s=r.peak_accel_time_s[i],
                    value=value,
                    bound=bound,
                )
            )
    if _over(r.sampled_accel_share, 1.0) and not found:
        found.append(_sampled_violation(r, "a_max", r.sampled_accel_share))
    if _over(r.sampled_speed_share, 1.0) and not _over(r.peak_speed_mps, r.v_max_mps):
        found.append(_sampled_violation(r, "v_max", r.sampled_speed_share))
    if _over(r.peak_speed_mps, r.v_max_mps):
        found.append(
            InfeasibleTrajectoryError(
                f"speed limit: {r.peak_speed_mps:.3f} m/s at t={r.peak_speed_time_s:.2f} s"
                f" (v_max {r.v_max_mps:.3f} m/s)",
                limit="v_max",
                axis=None,
                t_s=r.peak_speed_time_s,
                value=r.peak_speed_mps,
                bound=r.v_max_mps,
            )
        )
    if _over(r.peak_thrust_n, r.thrust_max_n):
        found.append(
            InfeasibleTrajectoryError(
                f"thrust limit: {r.peak_thrust_n:.2f} N (thrust_max {r.thrust_max_n:.2f} N)",
                limit="thrust",
                axis=None,
                t_s=0.0,
                value=r.peak_thrust_n,
                bound=r.thrust_max_n,
            )
        )
    if _over(r.body_rate_bound_radps, r.body_rate_max_radps):
        found.append(
            InfeasibleTrajectoryError(
                f"body-rate bound (eq. 15): {r.body_rate_bound_radps:.2f} rad/s"
                f" (max {r.body_rate_max_radps:.2f} rad/s); allow more time",
                limit="body_rate",
                axis=None,
                t_s=0.0,
                value=r.body_rate_bound_radps,
                bound=r.body_rate_max_radps,
            )
        )
    return found


def _sampled_violation(r: FeasibilityReport, limit: str, share: float) -> InfeasibleTrajectoryError:
    what = "acceleration" if limit == "a_max" else "speed"
    return InfeasibleTrajectoryError(
        f"{what} limit: sampled at {r.sampled_rate_hz:.0f} Hz it reaches {share:.4f} of its bound",
        limit=limit,
        axis=None,
        t_s=0.0,
        value=share,
        bound=1.0,
    )


def _span_polynomials(spline: ClampedCubicSpline) -> FloatArray:
    """Position polynomial of every span in ``x = u - span`` in [0, 1], shape (m, 4, 3)."""
    m = spline.n_spans
    table = span_coefficients(m)  # (m, 4 bases, 4 powers)
    idx = np.arange(m)[:, None] + np.arange(4)[None, :]
    return np.asarray(np.einsum("sap,sad->spd", table, spline.control_points[idx]))


def _speeds_sq(polynomials: FloatArray, x: FloatArray) -> FloatArray:
    """Squared speed (m, K) at ``x`` (K,) in [0, 1] on every span of the span ``polynomials``
    (m, 4, 3), in u units (times alpha^2 for time units): the hodograph polynomials (m, 3, 3)
    times the power rows (3, K)."""
    powers = np.stack([np.ones_like(x), 2.0 * x, 3.0 * x**2])  # d/dx of x, x^2, x^3
    hodograph = np.swapaxes(polynomials[:, 1:], 1, 2) @ powers
    return np.asarray(np.einsum("sdk,sdk->sk", hodograph, hodograph))


def _samples_per_span(spline: ClampedCubicSpline, rate_hz: float) -> int:
    """Samples per span, both ends included, for ``rate_hz`` or faster."""
    return max(2, math.ceil(rate_hz * spline.duration_s / spline.n_spans) + 1)


def _accel_share(accel_at_knots: FloatArray, limits: VehicleLimits) -> float:
    """Largest share of its bound of the acceleration, read at the knots (it is linear on each
    span, so no sample's share exceeds that of a span end)."""
    lower, upper = limits.accel_bounds_mps2()
    share = np.maximum(accel_at_knots / np.asarray(upper), accel_at_knots / np.asarray(lower))
    return float(np.max(share))


def _min_norm_on_segments(a0: FloatArray, a1: FloatArray) -> float:
    """min over x in [0,1] of ||a0 + x (a1 - a0)|| for rows of a0, a1 (n, 3)."""
    d = a1 - a0
    dd = np.sum(d * d, axis=1)
    x = np.clip(-np.sum(a0 * d, axis=1) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return float(np.min(np.linalg.norm(a0 + x[:, None] * d, axis=1)))


def _min_square_piecewise_linear(values: FloatArray) -> float:
    """min over t of v(t)^2 for a piecewise linear v with knot values ``values`` (n,)."""
    if np.any(np.sign(values[:-1]) * np.sign(values[1:]) <= 0):
        return 0.0
    return float(np.min(values**2))


def assess(
    spline: ClampedCubicSpline,
    limits: VehicleLimits,
    *,
    turning_residuals_m: FloatArray,
    turning_stroke_index: IntArray,
    n_strokes: int,
    board_surface_z_m: float,
    path_error_per_stroke_m: tuple[float, ...] = (),
) -> FeasibilityReport:
    """Measure ``spline`` against ``limits``; residuals are ``p(t_i) - d_i`` at turning points."""
    accel = spline.acceleration_at_knots()
    times = spline.knot_times_s()
    k_peak = np.argmax(np.abs(accel), axis=0)
    jerk = spline.jerk_per_span()
    lower, upper = limits.accel_bounds_mps2()
    specific = accel - _GRAVITY
    thrust_norm = np.linalg.norm(specific, axis=1)
    min_thrust = _min_norm_on_segments(specific[:-1], specific[1:]) * limits.mass_kg
    min_sq = sum(_min_square_piecewise_linear(specific[:, i]) for i in range(3))
    max_jerk_sq = float(np.sum(np.max(jerk**2, axis=0)))
    body_rate = math.sqrt(max_jerk_sq / min_sq) if min_sq > 0.0 else math.inf
    polynomials = _span_polynomials(spline)
    x = np.linspace(
        0.0, 1.0, max(PEAK_SAMPLES_PER_SPAN, _samples_per_span(spline, SAMPLED_RATE_HZ))
    )
    speeds_sq = _speeds_sq(polynomials, x)
    span, sample = np.unravel_index(int(np.argmax(speeds_sq)), speeds_sq.shape)
    speed = math.sqrt(float(speeds_sq[span, sample])) * spline.alpha
    heights = polynomials[:, :, 2] @ np.stack([np.ones_like(x), x, x**2, x**3])
    dist = np.linalg.norm(turning_residuals_m, axis=1)
    per_stroke = tuple(
        float(np.max(dist[turning_stroke_index == k], initial=0.0)) for k in range(n_strokes)
    )
    peak = np.abs(accel[k_peak, np.arange(3)])
    return FeasibilityReport(
        peak_accel_mps2=_tuple3(peak),
        peak_accel_time_s=_tuple3(times[k_peak]),
        accel_min_mps2=_tuple3(np.min(accel, axis=0)),
        accel_max_mps2=_tuple3(np.max(accel, axis=0)),
        accel_lower_mps2=lower,
        accel_upper_mps2=upper,
        peak_speed_mps=speed,
        peak_speed_time_s=float((span + x[sample]) / spline.alpha),
        v_max_mps=limits.v_max_mps,
        peak_thrust_n=float(np.max(thrust_norm)) * limits.mass_kg,
        min_thrust_n=min_thrust,
        thrust_max_n=limits.thrust_max_n,
        thrust_split_mps2=limits.thrust_split_mps2(),
        peak_jerk_mps3=_tuple3(np.max(np.abs(jerk), axis=0)),
        body_rate_bound_radps=body_rate,
        body_rate_max_radps=limits.body_rate_max_radps,
        fit_error_max_m=float(np.max(dist, initial=0.0)),
        fit_error_rms_m=float(np.sqrt(np.mean(dist**2))) if dist.size else 0.0,
        fit_error_max_per_stroke_m=per_stroke,
        min_height_above_board_m=float(np.min(heights)) - board_surface_z_m,
        path_error_max_per_stroke_m=path_error_per_stroke_m,
        sampled_rate_hz=SAMPLED_RATE_HZ,
        sampled_accel_share=_accel_share(accel, limits),
        sampled_speed_share=speed / limits.v_max_mps,
    )


def distance_to_polyline(xy: FloatArray, polyline: FloatArray) -> FloatArray:
    """Distance of points (n, 2) to the polyline (k, 2), shape (n,)."""
    if polyline.shape[0] == 1:
        return np.asarray(np.linalg.norm(xy - polyline[0], axis=1))
    a = polyline[:-1]
    ab = polyline[1:] - a  # (k - 1, 2)
    length_sq = np.sum(ab * ab, axis=1)
    along = np.sum((xy[:, None, :] - a) * ab, axis=2)  # (n, k - 1), every piece at once
    u = np.clip(along / np.where(length_sq > 0.0, length_sq, 1.0), 0.0, 1.0)
    u[:, length_sq <= 0.0] = 0.0
    offset = xy[:, None, :] - (a + u[:, :, None] * ab)
    return np.asarray(np.sqrt(np.min(np.sum(offset * offset, axis=2), axis=1)))


def path_errors(
    positions_m: FloatArray,
    times_s: FloatArray,
    pen_down: NDArray[np.bool_],
    stroke_intervals_s: tuple[tuple[float, float], ...],
    polylines_xy_m: tuple[FloatArray, ...],
) -> tuple[float, ...]:
    """Per stroke: largest horizontal distance of pen-down samples from the stroke's polyline."""
    located = located_path_errors(
        positions_m, times_s, pen_down, stroke_intervals_s, polylines_xy_m
    )
    return tuple(error for error, _ in located)


def located_path_errors(
    positions_m: FloatArray,
    times_s: FloatArray,
    pen_down: NDArray[np.bool_],
    stroke_intervals_s: tuple[tuple[float, float], ...],
    polylines_xy_m: tuple[FloatArray, ...],
) -> tuple[tuple[float, float], ...]:
    """Per stroke: (largest pen-down distance from its polyline [m], time of it [s]).

    A stroke without pen-down samples gives ``(0.0, t0)`` (``t0``: start of its interval).
    """
    located = []
    for (t0, t1), polyline in zip(stroke_intervals_s, polylines_xy_m, strict=True):
        mask = pen_down & (times_s >= t0) & (times_s <= t1)
        if not np.any(mask):
            located.append((0.0, t0))
            continue
        dist = distance_to_polyline(positions_m[mask, :2], polyline)
        worst = int(np.argmax(dist))
        located.append((float(dist[worst]), float(times_s[mask][worst])))
    return tuple(located)


def _tuple3(values: FloatArray) -> tuple[float, float, float]:
    return (float(values[0]), float(values[1]), float(values[2]))


def check(report: FeasibilityReport) -> None:
    """Raise the first :class:`InfeasibleTrajectoryError` of ``report``, if any."""
    found = report.violations()
    if found:
        raise found[0]
