"""Optimal time re-segmentation (section 5.4, eq. 55-56).

``f(T)`` is the optimal cost of the minimum-jerk fit when the data points are ``T_i`` apart in
time. Two ways to minimise it:

- :func:`descend_numerical` -- the paper's method: forward-difference gradient (eq. 56, one extra
  solve per segment, ``h = 1e-6``) and steepest descent with backtracking line search;
- :func:`descend_analytic` -- the gradient from the envelope theorem, one solve per step, and
  L-BFGS (planner.lbfgs) on ``log T`` (free total time) or on softmax weights (fixed
  total time).

Envelope theorem: at the optimum the derivative of ``f`` w.r.t. a data time needs only the
partial derivative of the cost at fixed control points. With ``r_i = p(t_i) - d_i`` and
``v_i = p'(t_i)``::

    df/dt_i = 2 w_i r_i . v_i            (knots fixed, i.e. alpha = m / sum T fixed)

which also holds with inequality constraints because they do not depend on the data times.
With a free total time ``alpha`` changes too and ``df/dalpha`` adds the jerk term
``5 w_g int j^2 / alpha``, the data term ``sum 2 w_i t_i r_i . v_i / alpha`` and the active
limits' multipliers (bounds scale as ``alpha^-e``). A free total time needs a time penalty
``rho sum T_i`` (Mellinger-Kumar): without it the jerk vanishes as ``T -> inf``.
Free-time re-segmentation assumes rest-to-rest ends (fixed control points independent of alpha).

Fixed total time: perturbations sum to zero (the paper's ``g_i`` with ``-1/(N-2)`` elsewhere;
softmax weights for L-BFGS). Every iterate keeps ``T_i >= t_min`` (``min_duration_s``, default
1 ms; without a floor the optimum may merge two data points in time, dropping one of them);
the result is never worse than the start (only decreasing steps are accepted).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.bspline import FloatArray
from planner.errors import InfeasibleTrajectoryError, PlannerError
from planner.fit_qp import QpFitter
from planner.lbfgs import minimize_lbfgs
from planner.minjerk import FitProblem, SplineFit, fit_closed_form

MAX_LOG_STEP = 2.0
"""Largest change of a log-duration (or softmax weight) per L-BFGS iteration: a duration
changes at most e^2 ~ 7.4 times per step (an unbounded quasi-Newton step once asked for fits
at exp(420) s, which have no spline)."""


class SegmentCost:
    """``f(T) = min_tau J(tau; T) (+ rho sum T)`` and its analytic gradient."""

    def __init__(
        self,
        template: FitProblem,
        *,
        fixed_total: bool,
        time_penalty: float = 0.0,
        fitter: QpFitter | None = None,
        min_duration_s: float = 1e-3,
    ) -> None:
        if not fixed_total and not (template.start.at_rest and template.end.at_rest):
            raise PlannerError("free-time re-segmentation needs rest-to-rest ends", field="start")
        if not fixed_total and time_penalty <= 0.0:
            raise PlannerError("a free total time needs a time penalty > 0", field="time_penalty")
        self.template = template
        self.fixed_total = fixed_total
        self.time_penalty = 0.0 if fixed_total else time_penalty
        self.fitter = fitter
        self.min_duration_s = min_duration_s
        self.evaluations = 0

    def fit(self, durations_s: FloatArray) -> SplineFit | None:
        """Optimal fit for durations (``None`` if the limits make it infeasible)."""
        self.evaluations += 1
        problem = self.template.with_durations(durations_s)
        if self.fitter is None:
            return fit_closed_form(problem)
        try:
            return self.fitter.fit(problem)
        except InfeasibleTrajectoryError:
            return None

    def value(self, durations_s: FloatArray, fit: SplineFit | None) -> float:
        """``f(T)``; ``inf`` when infeasible."""
        if fit is None:
            return math.inf
        return fit.cost + self.time_penalty * float(np.sum(durations_s))

    def __call__(self, durations_s: FloatArray) -> float:
        return self.value(durations_s, self.fit(durations_s))

    def gradient(self, durations_s: FloatArray, fit: SplineFit) -> FloatArray:
        """Analytic ``df/dT`` at the optimum ``fit`` for ``durations_s`` (envelope theorem)."""
        problem = self.template.with_durations(durations_s)
        w = problem.weights
        rv = np.sum(fit.residuals_m * fit.data_velocity_mps, axis=1)
        d_t = 2.0 * w * rv  # df/dt_i at fixed alpha
        grad = np.cumsum(d_t[::-1])[::-1][1:]  # t_i = sum_{j<i} T_j
        if self.fixed_total:
            return np.asarray(grad)
        total = problem.duration_s
        alpha = problem.alpha
        d_alpha = (
            5.0 * problem.jerk_weight_s5 * fit.jerk_cost + float(np.sum(d_t * problem.times_s))
        ) / alpha + fit.constraint_alpha_term
        return np.asarray(grad - d_alpha * alpha / total + self.time_penalty)


@dataclass(frozen=True)
class DescentResult:
    """Outcome of one minimisation of ``f(T)``."""

    durations_s: FloatArray
    """Best segment durations found, [s]."""
    fit: SplineFit
    """Optimal fit at those durations."""
    cost_initial: float
    """``f(T0)``."""
    cost_final: float
    """``f(T)`` at the result (never above ``cost_initial``)."""
    iterations: int
    """Descent iterations."""
    evaluations: int
    """Cost evaluations (solves)."""


def _descent_direction(
    grad: FloatArray, T: FloatArray, t_min: float, fixed_total: bool
) -> FloatArray:
    """``-grad`` projected on the zero-sum plane (fixed total) with durations at ``t_min`` that
    would shrink further held fixed (an active set), so the step is not cut to nothing."""
    free = np.ones(T.shape[0], dtype=bool)
    for _ in range(T.shape[0]):
        d = -grad.copy()
        d[~free] = 0.0
        if fixed_total and np.any(free):
            d[free] -= np.mean(d[free])
        blocked = free & (t_min * (1.0 + 1e-9) >= T) & (d < 0.0)
        if not np.any(blocked):
            return d
        free &= ~blocked
    return np.zeros_like(T)


def descend_numerical(
    cost: SegmentCost,
    durations_s: FloatArray,
    *,
    h: float = 1e-6,
    max_iter: int = 50,
    rel_tol: float = 1e-6,
) -> DescentResult:
    """The paper's method: forward differences along ``g_i`` (eq. 56), backtracking descent."""
    T = np.array(durations_s, dtype=np.float64)
    n = T.shape[0]
    start_evals = cost.evaluations
    fit = cost.fit(T)
    f0 = f = cost.value(T, fit)
    if fit is None:
        raise _infeasible_start()
    step = None
    iterations = 0
    for iterations in range(1, max_iter + 1):  # noqa: B007
        grad = np.empty(n)
        for i in range(n):
            g = np.full(n, -1.0 / max(n - 1, 1)) if cost.fixed_total else np.zeros(n)
            g[i] = 1.0
            grad[i] = (cost(T + h * g) - f) / h
        direction = _descent_direction(grad, T, cost.min_duration_s, cost.fixed_total)
        slope = float(direction @ grad)
        if not slope < 0.0:
            break
        step = step or 0.1 * float(np.min(T)) / float(np.max(np.abs(direction)))
        accepted = _backtrack(cost, T, f, direction, slope, step)
        if accepted is None:
            break
        T_new, fit_new, f_new, step = accepted
        decrease = f - f_new
        T, fit, f = T_new, fit_new, f_new
        step *= 2.0
        if decrease <= rel_tol * abs(f):
            break
    assert fit is not None
    return DescentResult(T, fit, f0, f, iterations, cost.evaluations - start_evals)


def _backtrack(
    cost: SegmentCost, T: FloatArray, f: float, direction: FloatArray, slope: float, step: float
) -> tuple[FloatArray, SplineFit, float, float] | None:
    """Armijo backtracking keeping every ``T_i >= t_min``; ``None`` when nothing decreases ``f``."""
    t_min = cost.min_duration_s
    negative = direction < 0.0
    for _ in range(30):
        trial = T + step * direction
        if np.any(negative):  # projected step: clip at t_min (the sum moves by < 1e-12 s)
            trial = np.maximum(trial, t_min)
            if cost.fixed_total:
                trial *= float(np.sum(T)) / float(np.sum(trial))
        fit = cost.fit(trial)
        value = cost.value(trial, fit)
        if fit is not None and value <= f + 1e-4 * step * slope:
            return trial, fit, value, step
        step *= 0.5
    return None


def _infeasible_start() -> PlannerError:
    return PlannerError("re-segmentation needs a feasible start", field="durations")


def descend_analytic(
    cost: SegmentCost,
    durations_s: FloatArray,
    *,
    max_iter: int = 100,
    rel_tol: float = 1e-7,
) -> DescentResult:
    """L-BFGS on ``log T`` (free) or softmax weights (fixed total) with the analytic gradient."""
    T0 = np.array(durations_s, dtype=np.float64)
    total = float(np.sum(T0))
    t_min = min(cost.min_duration_s, 0.5 * float(np.min(T0)))
    spare = total - t_min * T0.shape[0]  # fixed total: T = t_min + spare * softmax(theta)
    start_evals = cost.evaluations
    fit0 = cost.fit(T0)
    if fit0 is None:
        raise _infeasible_start()
    f0 = cost.value(T0, fit0)
    best: list[tuple[float, FloatArray, SplineFit]] = [(f0, T0, fit0)]
    to_durations: Callable[[FloatArray], FloatArray]
    if cost.fixed_total:

        def to_durations(theta: FloatArray) -> FloatArray:
            e = np.exp(theta - np.max(theta))
            return np.asarray(t_min + spare * e / np.sum(e))
    else:

        def to_durations(theta: FloatArray) -> FloatArray:
            return np.asarray(t_min + np.exp(theta))

    def objective(theta: FloatArray) -> tuple[float, FloatArray]:
        T = to_durations(theta)
        fit = cost.fit(T)
        value = cost.value(T, fit)
        if fit is None:
            return 1e300, np.zeros_like(theta)
        if value < best[0][0]:
            best[0] = (value, T, fit)
        g = cost.gradient(T, fit)
        x = T - t_min  # dT/dtheta: diag(x) (free), (diag(x) - x x^T / spare) (fixed)
        if cost.fixed_total:
            return value, np.asarray(x * (g - float(x @ g) / spare))
        return value, np.asarray(x * g)

    theta0 = np.log(T0 - t_min)
    res = minimize_lbfgs(
        objective, theta0, max_iter=max_iter, rel_tol=rel_tol, memory=20, max_step=MAX_LOG_STEP
    )
    f_best, T_best, fit_best = best[0]
    evaluations = cost.evaluations - start_evals
    return DescentResult(T_best, fit_best, f0, f_best, res.iterations, evaluations)
