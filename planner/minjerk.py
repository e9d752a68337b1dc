"""Minimum-jerk regression with a clamped cubic B-spline: the problem and its closed form.

Criterion (eq. 32/37, with per-point weights ``w_i``, all three axes at once)::

    J(tau) = w_g * int ||d^3 p/dt^3||^2 dt + sum_i w_i ||p(t_i) - d_i||^2
           = w_g tau^T G tau + (H tau - d)^T W (H tau - d)

The first and last three control points are fixed by the end states (eq. 38, 54); the others
follow from the normal equations ``R_PP tau_P = S_P^T - R_PF tau_F`` (eq. 43). ``R`` is banded
(3 super-diagonals) and shared by the three axes, so one band solve (planner.band_solve) solves
them all.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from planner.band_solve import solve_symmetric_band
from planner.bspline import (
    BasisRows,
    ClampedCubicSpline,
    FloatArray,
    IntArray,
    basis_rows,
    basis_rows_pair,
    jerk_gram_banded,
    span_jerk_u,
)
from planner.errors import PlannerError

MIN_SPANS = 4
"""At least one free control point between the six fixed by the end states."""


def _zeros3() -> FloatArray:
    return np.zeros(3)


@dataclass(frozen=True, eq=False)
class EndState:
    """Position, velocity and acceleration imposed at one end of the trajectory."""

    position_m: FloatArray
    """Position in [m], shape (3,)."""
    velocity_mps: FloatArray = field(default_factory=_zeros3)
    """Velocity in [m/s], shape (3,); zero for rest (the default)."""
    acceleration_mps2: FloatArray = field(default_factory=_zeros3)
    """Acceleration in [m/s^2], shape (3,); zero for rest (the default)."""

    @property
    def at_rest(self) -> bool:
        """True when velocity and acceleration are both zero."""
        return not (np.any(self.velocity_mps) or np.any(self.acceleration_mps2))


@dataclass(frozen=True, eq=False)
class FitProblem:
    """Data, times and spline size of one minimum-jerk regression."""

    times_s: FloatArray
    """Time of each data point in [s], shape (N,), within [0, duration_s]."""
    points_m: FloatArray
    """Data points ``d_i`` in [m], shape (N, 3)."""
    weights: FloatArray
    """Non-negative weight of each data point's squared error, shape (N,)."""
    n_spans: int
    """Number of unit knot spans ``m``; the spline has ``m + 3`` control points per axis."""
    duration_s: float
    """Total time ``T`` in [s]; ``alpha = m / T``."""
    jerk_weight_s5: float
    """``w_g`` of eq. (32) in [s^5]: squared jerk integral [m^2/s^5] against squared error [m^2]."""
    start: EndState
    """End state at ``t = 0``."""
    end: EndState
    """End state at ``t = T``."""

    def __post_init__(self) -> None:
        if self.n_spans < MIN_SPANS:
            raise PlannerError(f"needs >= {MIN_SPANS} spans, got {self.n_spans}", field="n_spans")
        if not self.duration_s > 0.0:
            raise PlannerError(f"duration must be > 0 s, got {self.duration_s}", field="duration")
        n = self.times_s.shape[0]
        if self.points_m.shape != (n, 3) or self.weights.shape != (n,):
            raise PlannerError("times, points and weights disagree in length", field="points")

    @property
    def alpha(self) -> float:
        """Knots per second ``m / T`` in [1/s]."""
        return self.n_spans / self.duration_s

    @property
    def n_ctrl(self) -> int:
        """Control points per axis."""
        return self.n_spans + 3

    def with_durations(self, segment_durations_s: FloatArray) -> FitProblem:
        """The same problem with data times ``t_0 = 0, t_{i+1} = t_i + T_i`` (eq. 55)."""
        times = np.concatenate([[0.0], np.cumsum(segment_durations_s)])
        return replace(self, times_s=times, duration_s=float(times[-1]))

    def segment_durations(self) -> FloatArray:
        """``T_i = t_{i+1} - t_i`` in [s], shape (N - 1,)."""
        return np.diff(self.times_s)


@dataclass(frozen=True, eq=False)
class SplineFit:
    """Optimal spline of a :class:`FitProblem` and the numbers the re-segmentation needs."""

    spline: ClampedCubicSpline
    """The fitted trajectory (control points shape (m + 3, 3))."""
    cost: float
    """``J`` at the optimum: ``w_g * jerk_cost + fit_cost``."""
    jerk_cost: float
    """``int ||jerk||^2 dt`` in [m^2/s^5]."""
    fit_cost: float
    """``sum_i w_i ||p(t_i) - d_i||^2`` in [m^2]."""
    residuals_m: FloatArray
    """``p(t_i) - d_i``, shape (N, 3)."""
    data_velocity_mps: FloatArray
    """``p'(t_i)``, shape (N, 3)."""
    constraint_alpha_term: float = 0.0
    """``sum_k mu_k * d(constraint_k)/d(alpha)`` from active inequality constraints (QP only)."""
    active_constraints: int = 0
    """Number of inequality constraints with a non-negligible multiplier (QP only)."""
    method: str = "closed-form"
    """``"closed-form"`` or the QP solver name."""


# --- banded normal equations ------------------------------------------------------------------


def banded_matvec(ab: FloatArray, x: FloatArray) -> FloatArray:
    """``R @ x`` for symmetric ``R`` in LAPACK upper banded storage with 3 super-diagonals."""
    n = ab.shape[1]
    bands = ab[:, :, None] if x.ndim == 2 else ab
    y = bands[3] * x
    for k in range(1, 4):
        band = bands[3 - k, k:]
        y[: n - k] += band * x[k:]
        y[k:] += band * x[: n - k]
    return np.asarray(y)


_PAIR_A = np.array([a for a in range(4) for _ in range(a, 4)])
_PAIR_B = np.array([b for a in range(4) for b in range(a, 4)])
_AXIS_OFFSET = np.arange(3)[None, None, :]


def normal_equations(
    problem: FitProblem, rows: BasisRows | None = None
) -> tuple[FloatArray, FloatArray]:
    """Banded ``R = w_g G + H^T W H`` (upper storage, shape (4, n)) and ``H^T W d`` (n, 3);
    ``rows``: the basis values at the data times when the caller has them."""
    n = problem.n_ctrl
    alpha = problem.alpha
    if rows is None:
        rows = basis_rows(alpha * problem.times_s, problem.n_spans)
    ab = problem.jerk_weight_s5 * alpha**5 * jerk_gram_banded(problem.n_spans)
    wv = problem.weights[:, None] * rows.values  # (N, 4)
    # Entry (first + a, first + b), a <= b, sits in band row 3 - (b - a), column first + b:
    # one bincount over flat indices (band row * n + column) for all 10 pairs at once.
    products = wv[:, _PAIR_A] * rows.values[:, _PAIR_B]  # (N, 10)
    flat = (3 - (_PAIR_B - _PAIR_A))[None, :] * n + rows.first[:, None] + _PAIR_B[None, :]
    ab += np.bincount(flat.ravel(), weights=products.ravel(), minlength=4 * n).reshape(4, n)
    # H^T W d: column first + a of axis k gets sum_i w_i v_ia d_ik.
    cols = rows.first[:, None, None] + np.arange(4)[None, :, None] + _AXIS_OFFSET * n
    contrib = wv[:, :, None] * problem.points_m[:, None, :]  # (N, 4, 3)
    rhs = np.bincount(cols.ravel(), weights=contrib.ravel(), minlength=3 * n).astype(np.float64)
    return ab, rhs.reshape(3, n).T.copy()


def fixed_indices(n_ctrl: int) -> IntArray:
    """Indices of the six control points fixed by the end states."""
    return np.array([0, 1, 2, n_ctrl - 3, n_ctrl - 2, n_ctrl - 1])


def fixed_control_points(problem: FitProblem) -> FloatArray:
    """Values (6, 3) of the fixed control points from position, velocity and acceleration.

    From ``p'(0) = 3 alpha (tau_1 - tau_0)`` and ``p''(0) = alpha^2 (6 tau_0 - 9 tau_1 + 3 tau_2)``
    (first rows of K and L), mirrored at the end.
    """
    alpha = problem.alpha
    s, e = problem.start, problem.end
    p0, v0, a0 = s.position_m, s.velocity_mps, s.acceleration_mps2
    p1, v1, a1 = e.position_m, e.velocity_mps, e.acceleration_mps2
    return np.array(
        [
            p0,
            p0 + v0 / (3.0 * alpha),
            p0 + v0 / alpha + a0 / (3.0 * alpha**2),
            p1 - v1 / alpha + a1 / (3.0 * alpha**2),
            p1 - v1 / (3.0 * alpha),
            p1,
        ]
    )


def evaluate_fit(
    problem: FitProblem,
    control_points: FloatArray,
    *,
    method: str = "closed-form",
    rows: tuple[BasisRows, BasisRows] | None = None,
) -> SplineFit:
    """Cost, residuals and data-point velocities of given control points (n_ctrl, 3);
    ``rows``: the basis values and slopes at the data times when the caller has them."""
    spline = ClampedCubicSpline(control_points=control_points, duration_s=problem.duration_s)
    alpha = problem.alpha
    if rows is None:
        rows = basis_rows_pair(alpha * problem.times_s, problem.n_spans)
    value_rows, slope_rows = rows
    residuals = value_rows.apply(control_points) - problem.points_m
    velocity = slope_rows.apply(control_points) * alpha
    jerk_u = span_jerk_u(control_points)
    jerk_cost = float(alpha**5 * np.sum(jerk_u**2))
    fit_cost = float(np.sum(problem.weights * np.sum(residuals**2, axis=1)))
    return SplineFit(
        spline=spline,
        cost=problem.jerk_weight_s5 * jerk_cost + fit_cost,
        jerk_cost=jerk_cost,
        fit_cost=fit_cost,
        residuals_m=residuals,
        data_velocity_mps=velocity,
        method=method,
    )


def fit_closed_form(problem: FitProblem) -> SplineFit:
    """Unconstrained minimum-jerk fit, eq. (43), by one band solve for all three axes."""
    rows = basis_rows_pair(problem.alpha * problem.times_s, problem.n_spans)
    ab, rhs = normal_equations(problem, rows[0])
    tau = closed_form_from_normal_equations(problem, ab, rhs)
    return evaluate_fit(problem, tau, rows=rows)


def closed_form_points(problem: FitProblem) -> tuple[FloatArray, FloatArray]:
    """Control points (n_ctrl, 3) of eq. (43) and the residuals ``p(t_i) - d_i`` (N, 3): the
    closed form without the rest of :class:`SplineFit` (costs, data-point velocities), for
    callers that evaluate many time allocations (planner.timescale)."""
    rows = basis_rows(problem.alpha * problem.times_s, problem.n_spans)
    ab, rhs = normal_equations(problem, rows)
    tau = closed_form_from_normal_equations(problem, ab, rhs)
    return tau, rows.apply(tau) - problem.points_m


def closed_form_from_normal_equations(
    problem: FitProblem, ab: FloatArray, rhs: FloatArray
) -> FloatArray:
    """Control points (n, 3) of eq. (43) given the banded ``R`` and ``H^T W d``."""
    n = problem.n_ctrl
    tau = np.zeros((n, 3))
    fixed = fixed_indices(n)
    tau[fixed] = fixed_control_points(problem)
    rhs_free = (rhs - banded_matvec(ab, tau))[3 : n - 3]
    tau[3 : n - 3] = solve_symmetric_band(ab[:, 3 : n - 3], rhs_free)
    return tau
