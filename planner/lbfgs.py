"""Limited-memory BFGS for the smooth, unbounded re-segmentation objectives (planner.retime).

Our own rather than SciPy's L-BFGS-B: importing ``scipy.optimize`` costs about 0.4 s, more than a
whole one-off ``skyquill plan``, for a method that fits in a page. Nocedal & Wright (2006),
algorithm 7.4 (two-loop recursion) and 3.1 (backtracking line search):

- direction ``-H g`` from the last ``memory`` pairs ``s = x_{k+1} - x_k``, ``y = g_{k+1} - g_k``,
  with the initial inverse Hessian scaled by ``s.y / y.y`` of the newest pair; the first step is
  steepest descent of length at most 1 (as L-BFGS-B starts);
- Armijo backtracking from the unit step, the next trial at the minimiser of the quadratic
  through ``f(x)``, the slope and the rejected value, kept within [0.1, 0.5] of the rejected
  step (an objective that answers ``inf`` or a huge value for an infeasible point only shrinks
  the step);
- no coordinate moves by more than ``max_step`` in one iteration (an objective that cannot be
  evaluated far from the current point, as a spline fit at ``exp(420)`` s, is never asked);
- a pair enters the memory only if it has positive curvature ``s.y > eps y.y`` (the Wolfe
  curvature condition that backtracking alone does not guarantee), which keeps ``H`` positive
  definite;
- stops like L-BFGS-B: relative decrease ``(f_k - f_{k+1}) / max(|f_k|, |f_{k+1}|, 1) <=
  rel_tol``, largest gradient component ``<= grad_tol``, ``max_iter`` iterations, or a line
  search that finds no decrease.

The problems have no bounds (planner.retime maps durations to unbounded log or softmax
parameters), so none are handled here.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from planner.bspline import FloatArray

Objective = Callable[[FloatArray], tuple[float, FloatArray]]
"""``x -> (f(x), grad f(x))``."""

_EPS = float(np.finfo(np.float64).eps)

ARMIJO_C1 = 1e-4
"""Sufficient decrease: accept ``f(x + a d) <= f(x) + c1 a (g . d)``."""


@dataclass(frozen=True)
class LbfgsResult:
    """The last accepted point of a minimisation and how it ended."""

    x: FloatArray
    """Last accepted point (the lowest value seen: only decreasing steps are accepted)."""
    value: float
    """``f(x)``."""
    gradient: FloatArray
    """``grad f(x)``."""
    iterations: int
    """Accepted steps."""
    evaluations: int
    """Calls of the objective (the start included)."""
    reason: str
    """``"rel_tol"``, ``"grad_tol"``, ``"max_iter"`` or ``"line_search"`` (no decrease found)."""


def _two_loop(grad: FloatArray, pairs: deque[tuple[FloatArray, FloatArray, float]]) -> FloatArray:
    """``H grad`` for the L-BFGS inverse Hessian ``H`` of ``pairs`` (s, y, 1 / s.y), oldest
    first."""
    q = grad.copy()
    alphas = []
    for s, y, rho in reversed(pairs):
        a = rho * float(s @ q)
        q -= a * y
        alphas.append(a)
    s_new, y_new, _ = pairs[-1]
    r = q * (float(s_new @ y_new) / float(y_new @ y_new))
    for (s, y, rho), a in zip(pairs, reversed(alphas), strict=True):
        r += s * (a - rho * float(y @ r))
    return r


def _next_step(step: float, value: float, trial_value: float, slope: float) -> float:
    """Backtracked step: minimiser of the quadratic through ``f(x)``, ``slope`` and the rejected
    ``trial_value`` at ``step``, kept within [0.1, 0.5] times ``step``."""
    curvature = trial_value - value - slope * step
    if not (math.isfinite(curvature) and curvature > 0.0):
        return 0.1 * step
    return min(0.5 * step, max(0.1 * step, -slope * step * step / (2.0 * curvature)))


def minimize_lbfgs(
    objective: Objective,
    x0: FloatArray,
    *,
    max_iter: int = 100,
    rel_tol: float = 1e-7,
    grad_tol: float = 1e-10,
    memory: int = 20,
    max_backtracks: int = 30,
    max_step: float = math.inf,
) -> LbfgsResult:
    """Minimise ``objective`` from ``x0`` (see the module docstring for the method)."""
    x = np.array(x0, dtype=np.float64)
    value, grad = objective(x)
    grad = np.asarray(grad, dtype=np.float64)
    evaluations = 1
    pairs: deque[tuple[FloatArray, FloatArray, float]] = deque(maxlen=memory)
    for iteration in range(max_iter):
        if float(np.max(np.abs(grad), initial=0.0)) <= grad_tol:
            return LbfgsResult(x, value, grad, iteration, evaluations, "grad_tol")
        direction = -_two_loop(grad, pairs) if pairs else -grad
        slope = float(direction @ grad)
        if not slope < 0.0:  # round-off spoilt H: restart from steepest descent
            pairs.clear()
            direction, slope = -grad, -float(grad @ grad)
        step = 1.0 if pairs else min(1.0, 1.0 / math.sqrt(-slope))
        step = min(step, max_step / float(np.max(np.abs(direction))))
        for _ in range(max_backtracks):
            trial = x + step * direction
            trial_value, trial_grad = objective(trial)
            evaluations += 1
            if trial_value <= value + ARMIJO_C1 * step * slope:
                break
            step = _next_step(step, value, trial_value, slope)
        else:
            return LbfgsResult(x, value, grad, iteration, evaluations, "line_search")
        trial_grad = np.asarray(trial_grad, dtype=np.float64)
        s, y = trial - x, trial_grad - grad
        sy = float(s @ y)
        if sy > _EPS * float(y @ y):
            pairs.append((s, y, 1.0 / sy))
        decrease = value - trial_value
        scale = max(abs(value), abs(trial_value), 1.0)
        x, value, grad = trial, trial_value, trial_grad
        if decrease <= rel_tol * scale:
            return LbfgsResult(x, value, grad, iteration + 1, evaluations, "rel_tol")
    return LbfgsResult(x, value, grad, max_iter, evaluations, "max_iter")
