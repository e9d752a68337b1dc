"""The fit held above the floor by an active set (planner.floor_qp) against PIQP solved tight,
the lazy QP's speed rows only where the ``v_max`` ball is left and its working set from the rows
the held fit breaks (planner.fit_qp), and LAPACK's band solver (planner.lapack_band) against the
plain-numpy one and a dense solve."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_planner_axis_qp import _tight_solve
from test_planner_band_solve import SIZES, _band
from test_planner_fit import _problem

from planner.band_solve import solve_symmetric_band_blocks
from planner.bspline import apply_band, velocity_values
from planner.fit_qp import QpFitter
from planner.floor_qp import principal_band, solve_floor
from planner.glyphs import fit_to_area, text_glyph
from planner.lapack_band import band_solver
from planner.minjerk import fit_closed_form, fixed_indices, normal_equations
from planner.pipeline import PlanOptions, prepare
from planner.qp_structure import SPEED_DIRECTIONS, SPEED_POLYTOPE_APOTHEM, QpLimits, build_qp
from planner.timing import allocate, point_tolerances_m

LOOSE = 50.0
"""Acceleration bound [m/s^2] no test fit comes near: only the floor binds."""


def _floor_limits(floor_m: float) -> QpLimits:
    return QpLimits((-LOOSE,) * 3, (LOOSE,) * 3, z_floor_m=floor_m)


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 10_000), m=st.integers(6, 90), share=st.floats(0.05, 0.9))
def test_the_active_set_is_the_qp_optimum_under_the_floor(seed: int, m: int, share: float) -> None:
    """A floor at a quantile of the free fit's z control points (so that it binds), the end
    points above it: the active set's fit is the QP's optimum (PIQP at 1e-12) and keeps the
    floor; x and y stay the closed form."""
    p = _problem(seed=seed, m=m, n_points=max(4, m // 2), duration=m / 4.0)
    free = fit_closed_form(p).spline.control_points
    ends = free[fixed_indices(p.n_ctrl), 2]
    floor = min(float(np.quantile(free[:, 2], share)), float(np.min(ends)) - 1e-3)
    fitter = QpFitter(_floor_limits(floor))
    fit = fitter.fit(p)
    qp = build_qp(p, _floor_limits(floor))
    exact = _tight_solve(qp)
    tau = fit.spline.control_points
    # The optimum's cost, not its argument: where the jerk term leaves a nearly flat valley the
    # argument is not unique to 1e-6 (seed 69, m 68, share 0.5: 3.8e-5 m apart at costs equal
    # to 2e-11 relative).
    upper = qp.P_upper.toarray()
    hessian = upper + np.triu(upper, 1).T

    def cost(x: np.ndarray) -> float:
        return float(0.5 * x @ hessian @ x + qp.c @ x)

    ours, best = cost(tau.T.ravel()), cost(exact.x)
    assert ours <= best + 1e-9 * (1.0 + abs(best))
    assert np.min(tau[:, 2]) >= floor - 1e-12
    np.testing.assert_array_equal(tau[:, :2], free[:, :2])
    if np.min(free[:, 2]) < floor:
        assert (fitter.floor_solves, fitter.solves) == (1, 0)  # no QP solve
        assert fit.method == "floor active set"


def test_a_floor_that_the_fit_keeps_changes_nothing() -> None:
    p = _problem(seed=2)
    ab, rhs = normal_equations(p)
    free = fit_closed_form(p).spline.control_points[:, 2]
    z = solve_floor(ab, rhs[:, 2], free, fixed_indices(p.n_ctrl), float(np.min(free)) - 1.0)
    assert z is not None
    np.testing.assert_array_equal(z, free)


def test_the_principal_band_is_the_dense_submatrix() -> None:
    dense, upper = _band(40, seed=5, definite=True)
    keep = np.array([0, 1, 3, 4, 5, 9, 10, 13, 20, 21, 22, 23, 39])
    sub = principal_band(upper, keep)
    expected = dense[np.ix_(keep, keep)]
    rebuilt = np.zeros_like(expected)
    for k in range(4):
        rebuilt += np.diag(sub[3 - k, k:], k) + (np.diag(sub[3 - k, k:], -k) if k else 0.0)
    np.testing.assert_array_equal(rebuilt, expected)


needs_lapack = pytest.mark.skipif(
    band_solver() is None, reason="numpy's LAPACK is not scipy-openblas: the numpy path solves"
)


@needs_lapack
@pytest.mark.parametrize("n", SIZES)
@pytest.mark.parametrize("definite", [True, False])
def test_lapack_and_the_block_solve_equal_the_dense_solve(n: int, definite: bool) -> None:
    """Both band solvers, indefinite matrices too, one right-hand side and several."""
    dense, upper = _band(n, seed=n, definite=definite)
    rhs = np.random.default_rng(1).normal(size=(n, 3))
    expected = np.linalg.solve(dense, rhs)
    scale = np.max(np.abs(expected))
    solve = band_solver()
    assert solve is not None
    for solver in (solve, solve_symmetric_band_blocks):
        np.testing.assert_allclose(solver(upper, rhs), expected, atol=1e-10 * scale)
        one = solver(upper, rhs[:, 0])
        assert one.shape == (n,)
        np.testing.assert_allclose(one, expected[:, 0], atol=1e-10 * scale)


@needs_lapack
def test_lapack_reports_a_singular_matrix_and_ignores_the_unused_corner() -> None:
    solve = band_solver()
    assert solve is not None
    dense, upper = _band(30, seed=3, definite=True)
    upper[0, :3] = upper[1, :2] = upper[2, :1] = np.nan
    np.testing.assert_allclose(solve(upper, np.ones(30)), np.linalg.solve(dense, np.ones(30)))
    with pytest.raises(np.linalg.LinAlgError, match="singular"):
        solve(np.zeros((4, 10)), np.ones(10))


def _hodograph_mps(tau: np.ndarray, alpha: float) -> np.ndarray:
    return apply_band(velocity_values(tau.shape[0] - 3), tau) * alpha


def test_speed_rows_are_imposed_only_where_the_ball_is_left() -> None:
    """v_max just above the free fit's fastest hodograph point, which lies outside the inscribed
    polytope: the lazy fitter keeps the free fit (the speed holds everywhere), the full QP,
    every polytope row imposed, bends it. Lowered below that point, the lazy fit is held to
    v_max (sampled densely)."""
    p = _problem(seed=7)
    free = fit_closed_form(p)
    hodograph = _hodograph_mps(free.spline.control_points, p.alpha)
    fastest = float(np.max(np.linalg.norm(hodograph, axis=1)))
    v_max = 1.001 * fastest
    assert np.max(np.abs(hodograph @ SPEED_DIRECTIONS.T)) > SPEED_POLYTOPE_APOTHEM * v_max
    limits = QpLimits((-LOOSE,) * 3, (LOOSE,) * 3, speed_max_mps=v_max)
    lazy = QpFitter(limits)
    kept = lazy.fit(p)
    assert lazy.solves == 0
    np.testing.assert_array_equal(kept.spline.control_points, free.spline.control_points)
    bent = QpFitter(limits, strategy="full").fit(p)
    assert np.max(np.abs(bent.spline.control_points - free.spline.control_points)) > 1e-4
    slow = QpLimits((-LOOSE,) * 3, (LOOSE,) * 3, speed_max_mps=0.8 * fastest)
    held = QpFitter(slow).fit(p).spline
    t = np.linspace(0.0, held.duration_s, 20_001)
    assert np.max(np.linalg.norm(held.evaluate(t, 1), axis=1)) <= 0.8 * fastest * (1 + 1e-9)


def test_a_fit_the_floor_bends_past_a_bound_is_solved_once_at_the_qp_optimum() -> None:
    """At 0.1 s knots and a jerk weight of 1e-5 s^5 the allocated fit of "i" breaks only the
    floor (a hop dips below the writing height), and held above it breaks z's acceleration
    bound: the QP's working set starts from the rows the held fit breaks, so one solve reaches
    the optimum of the QP with every acceleration row (it took two: the first imposed the
    floor alone, i.e. found the held fit again)."""
    strokes = fit_to_area(text_glyph("i"), width_m=1.0, height_m=1.0, margin_m=0.05).strokes
    options = PlanOptions(knot_spacing_s=0.1, jerk_weight_s5=1e-5)
    prep = prepare(strokes, options)
    limits = prep.qp_limits
    problem = allocate(
        prep.problem,
        prep.problem.weights,
        prep.problem.segment_durations(),
        options,
        limits,
        point_tolerances_m(prep.path, options),
    ).problem
    free = fit_closed_form(problem).spline
    assert limits.z_floor_m is not None
    assert np.min(free.control_points[:, 2]) < limits.z_floor_m  # the premise: a dip ...
    accel = free.acceleration_at_knots()
    assert np.all(accel <= limits.accel_upper_mps2) and np.all(accel >= limits.accel_lower_mps2)
    fitter = QpFitter(limits)
    fit = fitter.fit(problem)
    assert (fitter.floor_solves, fitter.solves, fit.method) == (0, 1, "piqp")  # ... bent past
    every_row = QpLimits(limits.accel_lower_mps2, limits.accel_upper_mps2, None, limits.z_floor_m)
    exact = QpFitter(every_row, strategy="full").fit(problem)
    np.testing.assert_allclose(fit.spline.control_points, exact.spline.control_points, atol=1e-6)
