"""Time re-segmentation (section 5.4): gradients, monotonicity, fixed/free total time."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from planner.errors import PlannerError
from planner.fit_qp import QpFitter
from planner.minjerk import EndState, FitProblem
from planner.qp_structure import QpLimits
from planner.retime import SegmentCost, descend_analytic, descend_numerical


def _problem(seed: int, n_points: int = 10, m: int = 30) -> FitProblem:
    rng = np.random.default_rng(seed)
    pts = np.cumsum(rng.normal(scale=0.3, size=(n_points, 3)), axis=0)
    durations = rng.uniform(0.6, 1.8, n_points - 1)
    times = np.concatenate([[0.0], np.cumsum(durations)])
    return FitProblem(
        times_s=times,
        points_m=pts,
        weights=np.ones(n_points),
        n_spans=m,
        duration_s=float(times[-1]),
        jerk_weight_s5=1e-2,
        start=EndState(pts[0]),
        end=EndState(pts[-1]),
    )


LIMITS = QpLimits((-0.5,) * 3, (0.5,) * 3, speed_max_mps=0.6)


def _costs(problem: FitProblem) -> dict[str, SegmentCost]:
    return {
        "closed-fixed": SegmentCost(problem, fixed_total=True),
        "closed-free": SegmentCost(problem, fixed_total=False, time_penalty=0.01),
        "qp-fixed": SegmentCost(problem, fixed_total=True, fitter=QpFitter(LIMITS)),
        "qp-free": SegmentCost(
            problem, fixed_total=False, time_penalty=0.01, fitter=QpFitter(LIMITS, strategy="full")
        ),
    }


@pytest.mark.parametrize("kind", ["closed-fixed", "closed-free", "qp-fixed", "qp-free"])
def test_analytic_gradient_matches_finite_differences(kind: str) -> None:
    problem = _problem(1)
    cost = _costs(problem)[kind]
    T = problem.segment_durations()
    fit = cost.fit(T)
    assert fit is not None
    if kind.startswith("qp"):
        assert fit.active_constraints > 0  # the multiplier terms are exercised
    analytic = cost.gradient(T, fit)
    h = 1e-6
    numeric = np.array([(cost(T + h * e) - cost(T - h * e)) / (2 * h) for e in np.eye(T.size)])
    if cost.fixed_total:  # only zero-sum perturbations are meaningful
        analytic, numeric = analytic - analytic.mean(), numeric - numeric.mean()
    # the QP is solved to ~1e-9: its finite differences carry that noise
    tol = 1e-4 if kind.startswith("qp") else 1e-6
    np.testing.assert_allclose(analytic, numeric, atol=tol * np.max(np.abs(numeric)))


@pytest.mark.parametrize("kind", ["closed-fixed", "closed-free", "qp-fixed"])
def test_analytic_and_numerical_descent_reach_the_same_optimum(kind: str) -> None:
    problem = _problem(2, n_points=7, m=24)
    T0 = problem.segment_durations()
    fast = descend_analytic(_costs(problem)[kind], T0, max_iter=200, rel_tol=1e-12)
    slow = descend_numerical(_costs(problem)[kind], T0, max_iter=300, rel_tol=1e-12)
    assert fast.cost_final < 0.9 * fast.cost_initial
    assert fast.cost_final == pytest.approx(slow.cost_final, rel=1e-6)
    np.testing.assert_allclose(fast.durations_s, slow.durations_s, rtol=1e-3, atol=1e-3)
    assert fast.evaluations < slow.evaluations


@settings(max_examples=12, deadline=None)
@given(
    st.integers(0, 10_000),
    st.sampled_from(["closed-fixed", "closed-free", "qp-fixed"]),
    st.sampled_from(["analytic", "numerical"]),
)
def test_resegmentation_never_increases_cost(seed: int, kind: str, method: str) -> None:
    problem = _problem(seed, n_points=6, m=20)
    cost = _costs(problem)[kind]
    T0 = problem.segment_durations()
    if cost(T0) == np.inf:
        return
    descend = descend_analytic if method == "analytic" else descend_numerical
    result = descend(cost, T0, max_iter=15)
    assert result.cost_final <= result.cost_initial
    assert cost(result.durations_s) == pytest.approx(result.cost_final, rel=1e-6, abs=1e-12)
    assert np.all(result.durations_s > 0.0)
    if cost.fixed_total:
        assert np.sum(result.durations_s) == pytest.approx(np.sum(T0), rel=1e-12)


def test_free_time_descent_never_asks_for_a_fit_at_an_absurd_duration() -> None:
    """Seed 9999: an unbounded quasi-Newton step once asked for durations of exp(420) s (no
    spline: singular normal equations); the log-step cap keeps every trial reasonable."""
    problem = _problem(9999, n_points=6, m=20)
    cost = _costs(problem)["closed-free"]
    T0 = problem.segment_durations()
    result = descend_analytic(cost, T0, max_iter=15)
    assert result.cost_final <= result.cost_initial
    assert np.all(result.durations_s < 100.0 * np.max(T0))


def test_free_time_needs_a_penalty() -> None:
    with pytest.raises(PlannerError):
        SegmentCost(_problem(0), fixed_total=False, time_penalty=0.0)
