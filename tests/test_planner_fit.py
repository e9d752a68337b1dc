"""Minimum-jerk fits: closed form (eq. 43) against a dense solve, the QP (eq. 44-54) and limits."""

from __future__ import annotations

import numpy as np
import pytest

from planner.bspline import basis_rows, jerk_gram
from planner.errors import InfeasibleTrajectoryError
from planner.fit_qp import QpFitter, dense_qp_seconds
from planner.minjerk import EndState, FitProblem, fit_closed_form, fixed_indices
from planner.qp_solvers import PiqpBackend, make_backend
from planner.qp_structure import QpLimits, build_qp


def _problem(
    seed: int = 0,
    n_points: int = 25,
    m: int = 60,
    duration: float = 15.0,
    start: EndState | None = None,
    end: EndState | None = None,
) -> FitProblem:
    rng = np.random.default_rng(seed)
    t = np.sort(rng.uniform(0.0, duration, n_points))
    t[0], t[-1] = 0.0, duration
    d = np.cumsum(rng.normal(scale=0.15, size=(n_points, 3)), axis=0)
    return FitProblem(
        times_s=t,
        points_m=d,
        weights=rng.uniform(0.5, 2.0, n_points),
        n_spans=m,
        duration_s=duration,
        jerk_weight_s5=1e-3,
        start=start or EndState(d[0]),
        end=end or EndState(d[-1]),
    )


def test_closed_form_equals_dense_normal_equations() -> None:
    p = _problem()
    fit = fit_closed_form(p)
    H = basis_rows(p.alpha * p.times_s, p.n_spans).toarray()
    W = np.diag(p.weights)
    R = p.jerk_weight_s5 * jerk_gram(p.n_spans, p.alpha) + H.T @ W @ H
    fixed = fixed_indices(p.n_ctrl)
    free = np.setdiff1d(np.arange(p.n_ctrl), fixed)
    tau = fit.spline.control_points
    # eq. (43): R_PP tau_P = S_P^T - R_PF tau_F
    rhs = (H.T @ W @ p.points_m)[free] - R[np.ix_(free, fixed)] @ tau[fixed]
    np.testing.assert_allclose(R[np.ix_(free, free)] @ tau[free], rhs, atol=1e-9)
    cost = np.einsum("ia,ij,ja->", tau, R, tau) - 2 * np.sum(p.points_m * (W @ H @ tau))
    assert fit.cost == pytest.approx(cost + np.sum(p.weights[:, None] * p.points_m**2), rel=1e-9)


def test_end_states_are_met() -> None:
    start = EndState(
        np.array([0.1, 0.2, 1.0]), np.array([0.3, -0.1, 0.0]), np.array([0, 0.2, -0.1])
    )
    end = EndState(np.array([1.0, -0.5, 1.2]), np.array([-0.2, 0.0, 0.1]), np.array([0.1, 0, 0]))
    p = _problem(start=start, end=end)
    s = fit_closed_form(p).spline
    ends = np.array([0.0, p.duration_s])
    np.testing.assert_allclose(s.evaluate(ends, 0), [start.position_m, end.position_m], atol=1e-12)
    np.testing.assert_allclose(
        s.evaluate(ends, 1), [start.velocity_mps, end.velocity_mps], atol=1e-9
    )
    np.testing.assert_allclose(
        s.evaluate(ends, 2), [start.acceleration_mps2, end.acceleration_mps2], atol=1e-9
    )


LOOSE = QpLimits((-50.0,) * 3, (50.0,) * 3, speed_max_mps=50.0)


@pytest.mark.parametrize("solver", ["piqp", "clarabel", "osqp"])
@pytest.mark.parametrize("strategy", ["lazy", "full"])
def test_qp_equals_closed_form_without_active_limits(solver: str, strategy: str) -> None:
    p = _problem(seed=2)
    closed = fit_closed_form(p)
    qp = QpFitter(LOOSE, solver, strategy).fit(p)
    np.testing.assert_allclose(qp.spline.control_points, closed.spline.control_points, atol=1e-5)
    assert qp.cost == pytest.approx(closed.cost, rel=1e-6)
    assert qp.active_constraints == 0


TIGHT = QpLimits((-0.3, -0.3, -0.2), (0.3, 0.3, 0.25), speed_max_mps=0.35, z_floor_m=-0.4)


@pytest.mark.parametrize("solver", ["piqp", "clarabel"])
@pytest.mark.parametrize("strategy", ["lazy", "full"])
def test_qp_respects_limits_when_sampled_densely(solver: str, strategy: str) -> None:
    p = _problem(seed=4)
    closed = fit_closed_form(p)
    assert np.max(np.abs(closed.spline.acceleration_at_knots())) > 0.35  # limits bite
    fit = QpFitter(TIGHT, solver, strategy).fit(p)
    assert fit.active_constraints > 0
    assert fit.cost > closed.cost
    t = np.linspace(0.0, p.duration_s, 20001)
    a = fit.spline.evaluate(t, 2)
    assert np.all(a <= np.array(TIGHT.accel_upper_mps2) + 1e-6)
    assert np.all(a >= np.array(TIGHT.accel_lower_mps2) - 1e-6)
    assert np.max(np.linalg.norm(fit.spline.evaluate(t, 1), axis=1)) <= 0.35 + 1e-6
    assert np.min(fit.spline.evaluate(t)[:, 2]) >= -0.4 - 1e-9
    ends = fit.spline.evaluate(np.array([0.0, p.duration_s]), 1)
    np.testing.assert_allclose(ends, 0.0, atol=1e-7)


def test_lazy_and_full_qp_agree_and_solvers_agree() -> None:
    p = _problem(seed=4)
    costs = [
        QpFitter(TIGHT, s, strat).fit(p).cost
        for s in ("piqp", "clarabel", "osqp")
        for strat in ("lazy", "full")
    ]
    np.testing.assert_allclose(costs, costs[0], rtol=1e-5)


@pytest.mark.parametrize("strategy", ["lazy", "full"])
def test_piqp_dense_interface_solves_like_the_sparse_one(strategy: str) -> None:
    p = _problem(seed=4)
    sparse = QpFitter(TIGHT, "piqp", strategy).fit(p)
    dense = QpFitter(TIGHT, "piqp", strategy, dense_budget_s=10.0).fit(p)
    np.testing.assert_allclose(dense.spline.control_points, sparse.spline.control_points, atol=1e-9)
    assert dense.active_constraints == sparse.active_constraints > 0
    assert dense.constraint_alpha_term == pytest.approx(sparse.constraint_alpha_term, rel=1e-6)


def test_the_dense_budget_is_spent_then_the_sparse_interface_kept() -> None:
    """Dense while the predicted time fits; from the first QP that does not, sparse for good
    (SciPy is loaded then), even for a QP small enough for what is left."""
    one_solve_s = dense_qp_seconds(100, 20)
    assert dense_qp_seconds(100, 200) > one_solve_s > dense_qp_seconds(100, 0)  # rows cost too
    fitter = QpFitter(TIGHT, "piqp", dense_budget_s=1.5 * one_solve_s)
    chosen = [fitter._dense_for(one_solve_s) for _ in range(2)]
    chosen += [fitter._dense_for(dense_qp_seconds(10, 0))]
    assert [b is not None for b in chosen] == [True, False, False] and fitter._dense is None
    assert isinstance(fitter._sparse, PiqpBackend)
    assert QpFitter(TIGHT, "piqp")._dense_for(dense_qp_seconds(10, 0)) is None


def test_full_qp_matches_paper_structure() -> None:
    p = _problem(seed=1, m=20)
    qp = build_qp(p, TIGHT)
    n = p.n_ctrl
    assert qp.P_upper.shape == (3 * n, 3 * n)
    assert qp.A.shape == (18, 3 * n)  # eq. (54): first and last three per axis
    assert qp.G.shape[0] == 3 * (p.n_spans + 1) + 13 * (n - 1)  # eq. (53) rows + speed rows
    sol = make_backend("piqp").solve(qp)
    assert sol.status == "solved"


def test_infeasible_qp_names_the_limit() -> None:
    d = np.array([[0.0, 0.0, 1.0], [3.0, 0.0, 1.0]])
    p = FitProblem(
        times_s=np.array([0.0, 2.0]),
        points_m=d,
        weights=np.ones(2),
        n_spans=8,
        duration_s=2.0,
        jerk_weight_s5=1e-3,
        start=EndState(d[0]),
        end=EndState(d[1]),
    )
    with pytest.raises(InfeasibleTrajectoryError) as info:
        QpFitter(QpLimits((-1.0,) * 3, (1.0,) * 3)).fit(p)
    assert info.value.limit == "a_max"
    assert info.value.axis == "x"
    assert abs(info.value.value) > 1.0


def test_speed_polytope_is_inscribed_in_the_ball() -> None:
    """|n_k . v| <= apothem for all 13 directions implies ||v|| <= 1 (the QP's speed rows)."""
    from planner.qp_structure import SPEED_DIRECTIONS, SPEED_POLYTOPE_APOTHEM

    assert SPEED_DIRECTIONS.shape == (13, 3)
    u = np.random.default_rng(0).normal(size=(20000, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    support = np.max(np.abs(u @ SPEED_DIRECTIONS.T), axis=1)  # largest projection of a unit vector
    assert np.min(support) >= SPEED_POLYTOPE_APOTHEM - 1e-12
    # and the bound is tight: a vertex direction (1, 1, sqrt(2)-ish) gets close to it
    assert np.min(support) < SPEED_POLYTOPE_APOTHEM * 1.01
