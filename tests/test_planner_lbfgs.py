"""Our L-BFGS (planner.lbfgs): textbook minima, closed-form quadratics, and SciPy's L-BFGS-B on
real re-segmentation problems (SciPy imported only here, as the reference)."""

from __future__ import annotations

import numpy as np
import pytest

from planner.bspline import FloatArray
from planner.glyphs import fit_to_area, text_glyph
from planner.lbfgs import minimize_lbfgs
from planner.minjerk import fit_closed_form
from planner.options import PlanOptions
from planner.pipeline import prepare
from planner.retime import SegmentCost, descend_analytic
from planner.timescale import stationary_time_penalty


def _rosenbrock(x: FloatArray) -> tuple[float, FloatArray]:
    """Chained Rosenbrock function and its gradient (minimum 0 at all ones)."""
    a, b = x[:-1], x[1:]
    value = float(np.sum(100.0 * (b - a**2) ** 2 + (1.0 - a) ** 2))
    grad = np.zeros_like(x)
    grad[:-1] += -400.0 * a * (b - a**2) - 2.0 * (1.0 - a)
    grad[1:] += 200.0 * (b - a**2)
    return value, grad


@pytest.mark.parametrize("dim", [2, 6])
def test_rosenbrock_minimum(dim: int) -> None:
    x0 = np.tile([-1.2, 1.0], dim // 2)
    res = minimize_lbfgs(_rosenbrock, x0, max_iter=500, rel_tol=1e-15, grad_tol=1e-9)
    np.testing.assert_allclose(res.x, np.ones(dim), atol=1e-5)
    assert res.value < 1e-10
    assert res.reason in ("grad_tol", "rel_tol")


@pytest.mark.parametrize("seed", range(5))
def test_random_convex_quadratic_matches_the_closed_form(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 12
    q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    hessian = q @ np.diag(np.geomspace(0.1, 100.0, n)) @ q.T  # condition number 1000
    b = rng.normal(size=n)

    def quadratic(x: FloatArray) -> tuple[float, FloatArray]:
        return 0.5 * float(x @ hessian @ x) - float(b @ x), hessian @ x - b

    res = minimize_lbfgs(quadratic, rng.normal(size=n), max_iter=300, rel_tol=0.0)
    optimum = np.linalg.solve(hessian, b)
    # f is flat to round-off within ~1e-7 of the optimum along the weakest eigenvector
    np.testing.assert_allclose(res.x, optimum, rtol=1e-5, atol=1e-6)
    assert res.value - quadratic(optimum)[0] <= 1e-12 * abs(res.value)


def test_backtracks_out_of_an_infeasible_region() -> None:
    """Trial points past a wall answer a huge value (as an infeasible fit does): the search
    shrinks its step and still reaches the minimum just inside the wall."""
    beyond_wall = []

    def walled(x: FloatArray) -> tuple[float, FloatArray]:
        if x[0] > 1.0:
            beyond_wall.append(x)
            return 1e300, np.zeros_like(x)
        r = x - np.array([0.4, 0.0])
        h = np.sqrt(1.0 + r**2)  # pseudo-Huber: nearly flat far out, so secant steps overshoot
        return float(np.sum(h)), r / h

    res = minimize_lbfgs(walled, np.array([-30.0, 10.0]), max_iter=100, rel_tol=1e-14)
    assert beyond_wall  # the wall was hit
    np.testing.assert_allclose(res.x, [0.4, 0.0], atol=1e-6)


def test_no_coordinate_moves_more_than_max_step_per_iteration() -> None:
    def downhill(x: FloatArray) -> tuple[float, FloatArray]:
        return -float(np.sum(x)), -np.ones_like(x)

    res = minimize_lbfgs(downhill, np.zeros(2), max_iter=3, max_step=0.5)
    np.testing.assert_allclose(res.x, [1.5, 1.5])
    assert res.reason == "max_iter"


def _scipy_descent(cost: SegmentCost, durations_s: FloatArray) -> float:
    """Final cost of the former re-segmentation: SciPy's L-BFGS-B on the same objective."""
    from scipy.optimize import minimize

    best = [cost(durations_s)]
    T0 = np.array(durations_s, dtype=np.float64)
    t_min = min(cost.min_duration_s, 0.5 * float(np.min(T0)))
    spare = float(np.sum(T0)) - t_min * T0.shape[0]

    def objective(theta: FloatArray) -> tuple[float, FloatArray]:
        if cost.fixed_total:
            e = np.exp(theta - np.max(theta))
            T = t_min + spare * e / np.sum(e)
        else:
            T = t_min + np.exp(theta)
        fit = cost.fit(T)
        if fit is None:
            return 1e300, np.zeros_like(theta)
        value = cost.value(T, fit)
        best[0] = min(best[0], value)
        g = cost.gradient(T, fit)
        x = T - t_min
        if cost.fixed_total:
            return value, x * (g - float(x @ g) / spare)
        return value, x * g

    minimize(
        objective,
        np.log(T0 - t_min),
        jac=True,
        method="L-BFGS-B",
        options={"maxiter": 100, "ftol": 1e-7, "gtol": 1e-10, "maxcor": 20},
    )
    return best[0]


@pytest.mark.parametrize("char", ["A", "g", "永"])
@pytest.mark.parametrize("fixed_total", [True, False])
def test_resegmentation_reaches_scipy_cost(char: str, fixed_total: bool) -> None:
    strokes = fit_to_area(text_glyph(char), width_m=1.0, height_m=1.0, margin_m=0.05).strokes
    options = PlanOptions(pace="nominal")
    problem = prepare(strokes, options).problem
    rho = 0.0 if fixed_total else stationary_time_penalty(fit_closed_form(problem), problem)

    def cost() -> SegmentCost:
        return SegmentCost(
            problem,
            fixed_total=fixed_total,
            time_penalty=rho,
            min_duration_s=options.min_segment_time_s,
        )

    T0 = problem.segment_durations()
    ours = descend_analytic(cost(), T0)
    reference = _scipy_descent(cost(), T0)
    assert ours.cost_final < ours.cost_initial
    assert ours.cost_final <= reference * 1.005
