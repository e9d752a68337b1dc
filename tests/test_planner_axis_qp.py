"""The minimum-jerk QP solved axis by axis (planner.axis_qp) against the coupled QP it splits."""

from __future__ import annotations

from typing import Any

import numpy as np
import piqp
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from test_planner_fit import TIGHT, _problem

from planner.axis_qp import axis_qp, joined, row_axes
from planner.fit_qp import QpFitter
from planner.minjerk import FitProblem
from planner.qp_solvers import QpData, QpSolution
from planner.qp_structure import QpLimits, build_qp


def _tight_solve(qp: QpData) -> QpSolution:
    """PIQP's dense solve to 1e-12: close enough to the exact optimum that a split which
    changes the problem shows, and one which does not agrees to round-off."""
    solver = piqp.DenseSolver()
    settings_: Any = solver.settings
    settings_.verbose = False
    for name in ("eps_abs", "eps_rel", "eps_duality_gap_abs", "eps_duality_gap_rel"):
        setattr(settings_, name, 1e-12)
    dense = [np.asfortranarray(m.toarray()) for m in (qp.P_upper, qp.A, qp.G)]
    solver.setup(dense[0], qp.c, dense[1], qp.b, dense[2], qp.h_l, qp.h_u, qp.x_l, qp.x_u)
    status = solver.solve()
    result = solver.result
    return QpSolution(
        x=np.array(result.x),
        z=np.array(result.z_u) - np.array(result.z_l),
        status="solved" if status == piqp.PIQP_SOLVED else str(status),
        iterations=int(result.info.iter),
        solve_ms=0.0,
    )


def _limits(p: FitProblem, a_max_mps2: float, floor: bool) -> QpLimits:
    """Acceleration limits of ``a_max_mps2`` (z: less), a floor just under the lower end, if any."""
    lower = (-a_max_mps2, -a_max_mps2, -0.6 * a_max_mps2)
    upper = (a_max_mps2, 0.9 * a_max_mps2, 0.7 * a_max_mps2)
    ends_z = (p.start.position_m[2], p.end.position_m[2])
    return QpLimits(lower, upper, z_floor_m=min(ends_z) - 0.05 if floor else None)


def test_rows_of_one_axis_are_told_apart_from_rows_that_couple() -> None:
    p = _problem(seed=1, m=20)
    n = p.n_ctrl
    accel = build_qp(p, _limits(p, 0.3, floor=True)).G
    axes = row_axes(accel, n)
    assert axes is not None
    np.testing.assert_array_equal(axes, np.repeat(np.arange(3), p.n_spans + 1))
    assert row_axes(build_qp(p, TIGHT).G, n) is None  # the speed polytope's diagonals
    assert row_axes(accel.take_rows(np.array([], dtype=np.int64)), n).shape == (0,)


def _assert_optimal_in(qp: QpData, sol: QpSolution) -> None:
    """``sol`` (primal, row multipliers) is a KKT point of ``qp`` (finite row bounds): stationary
    along every variable that no equality holds and that is off its box, each multiplier
    complementary to its row's slack. (Multipliers are not unique where active rows are
    degenerate, so they are not compared with another solve's.)"""
    upper = qp.P_upper.toarray()
    G = qp.G.toarray()
    gradient = (upper + upper.T - np.diag(np.diag(upper))) @ sol.x + qp.c + G.T @ sol.z
    free = sol.x > qp.x_l + 1e-4
    free[qp.A.cols] = False
    np.testing.assert_allclose(gradient[free], 0.0, atol=1e-9 * max(1.0, np.max(np.abs(qp.c))))
    g = G @ sol.x
    slack_products = np.maximum(sol.z, 0.0) * (qp.h_u - g) - np.minimum(sol.z, 0.0) * (g - qp.h_l)
    assert np.max(np.abs(slack_products), initial=0.0) <= 1e-9


@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    m=st.integers(8, 80),
    a_max_mps2=st.floats(0.05, 1.0),
    floor=st.booleans(),
)
def test_the_axes_solved_apart_are_the_coupled_qp(
    seed: int, m: int, a_max_mps2: float, floor: bool
) -> None:
    """The joined solution, its multipliers in the coupled QP's row order, is the coupled QP's
    optimum; infeasible exactly when the coupled QP is (then one axis is)."""
    p = _problem(seed=seed, m=m, n_points=max(4, m // 2), duration=m / 4.0)
    qp = build_qp(p, _limits(p, a_max_mps2, floor))
    axes = row_axes(qp.G, p.n_ctrl)
    assert axes is not None
    coupled = _tight_solve(qp)
    split = joined([_tight_solve(axis_qp(qp, a, p.n_ctrl, axes)) for a in range(3)], axes)
    assert (split.status == "solved") == (coupled.status == "solved")
    if coupled.status == "solved":
        np.testing.assert_allclose(split.x, coupled.x, atol=1e-5)
        _assert_optimal_in(qp, split)


def _counting_dense_solves(fitter: QpFitter) -> list[int]:
    """The sizes (variables) of the QPs ``fitter`` solves on the dense interface, as it goes."""
    dense = fitter._dense
    assert dense is not None
    solve = dense.solve
    sizes: list[int] = []

    def counted(qp: QpData) -> QpSolution:
        sizes.append(qp.c.shape[0])
        return solve(qp)

    dense.solve = counted  # type: ignore[method-assign]
    return sizes


@pytest.mark.parametrize("dense_budget_s", [0.0, 10.0])
@pytest.mark.parametrize("strategy", ["lazy", "full"])
def test_the_fitter_splits_dense_solves_without_speed_rows_and_agrees(
    dense_budget_s: float, strategy: str
) -> None:
    """Dense: axis by axis; sparse: coupled. Both reach the optimum of the coupled QP (to PIQP's
    default tolerance, at which each axis's iterations stop on their own), its cost and alpha
    term."""
    p = _problem(seed=4)
    limits = _limits(p, 0.3, floor=True)
    fitter = QpFitter(limits, "piqp", strategy, dense_budget_s=dense_budget_s)
    sizes = _counting_dense_solves(fitter) if dense_budget_s else []
    fit = fitter.fit(p)
    coupled = _tight_solve(build_qp(p, limits))
    np.testing.assert_allclose(fit.spline.control_points.T.ravel(), coupled.x, atol=1e-5)
    assert fit.active_constraints > 0
    idle_speed = QpLimits(limits.accel_lower_mps2, limits.accel_upper_mps2, 50.0, limits.z_floor_m)
    coupled_fit = QpFitter(idle_speed, "piqp", "full").fit(p)  # every speed row: coupled
    assert fit.cost == pytest.approx(coupled_fit.cost, rel=1e-7)
    assert fit.constraint_alpha_term == pytest.approx(coupled_fit.constraint_alpha_term, rel=1e-5)
    if dense_budget_s:
        assert sizes and set(sizes) == {p.n_ctrl}  # every dense solve one axis's QP


def test_an_axis_without_rows_is_its_closed_form_and_costs_no_solve() -> None:
    """A floor that the free fit breaks, no acceleration row: x and y keep their closed form,
    z alone is held above the floor, by the active set of planner.floor_qp (no QP solve)."""
    p = _problem(seed=3)
    z_free = QpFitter(QpLimits((-50.0,) * 3, (50.0,) * 3)).fit(p).spline.control_points[:, 2]
    floor = float(np.quantile(z_free, 0.2))
    limits = QpLimits((-50.0,) * 3, (50.0,) * 3, z_floor_m=floor)
    fitter = QpFitter(limits, dense_budget_s=10.0)
    sizes = _counting_dense_solves(fitter)
    fit = fitter.fit(p)
    assert (fitter.floor_solves, fitter.solves, sizes) == (1, 0, [])  # no QP, dense or sparse
    assert np.min(fit.spline.control_points[:, 2]) >= floor - 1e-7
    coupled = _tight_solve(build_qp(p, limits))
    np.testing.assert_allclose(fit.spline.control_points.T.ravel(), coupled.x, atol=1e-6)


def test_a_budget_too_small_for_the_axes_solves_the_coupled_qp_sparse() -> None:
    """Once the dense budget cannot hold a QP's solves, that QP and every later one go to the
    sparse interface, coupled (its pattern kept from one re-solve to the next)."""
    p = _problem(seed=4)
    fitter = QpFitter(_limits(p, 0.3, floor=True), "piqp", dense_budget_s=1e-9)
    fit = fitter.fit(p)
    assert fitter._dense is None and fit.active_constraints > 0
