"""Contact-aware motion-force planning of the hexarotor (paper eq. 7)."""

from __future__ import annotations

import dataclasses
import re

import casadi as ca
import numpy as np
import pytest

from planner.errors import InfeasibleTrajectoryError, PlannerError
from vehicles.hexarotor_sponge import nlp, period_cache, period_nlp, solver_cache, steps
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.nlp import solve_period
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.plan import PlanSettings, plan_writing
from vehicles.hexarotor_sponge.waypoints import Period, periods_of
from vehicles.kind import StrokeInput
from vehicles.surface import Surface

SURFACE = Surface.of("vertical", (0.0, 3.0, 2.0), 0.0)
PARAMS = HexarotorParams()
PAPER = Limits(corridor_m=None)
"""The paper's eq. 7 (positions pinned at the waypoints only)."""


def test_contact_phases_follow_waypoint_forces() -> None:
    strokes = [
        StrokeInput(np.array([[0.0, 0.0], [0.1, 0.0]])),
        StrokeInput(np.array([[0.0, 0.1], [0.0, 0.2]])),
    ]
    forces = [np.array([2.0, 3.0]), np.array([1.5, 1.5])]
    periods = periods_of(strokes, forces, start_m=np.array([0.0, 0.0, 0.06]), standoff_m=0.03)
    assert [p.contact for p in periods] == [False, True, False, True, False]
    for p in periods:
        if p.contact:
            assert np.all(p.points_m[:, 2] == 0.0)
            assert p.force_n[0] == 0.0 and p.force_n[-1] == 0.0
            assert np.all(p.force_n[1:-1] > 0.0)
        else:
            assert np.all(p.force_n == 0.0)
            assert np.all(p.points_m[1:-1, 2] > 0.0)
    assert periods[1].force_n.tolist() == [0.0, 2.0, 3.0, 0.0]


def test_zero_force_on_a_contact_stroke_is_refused() -> None:
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.1, 0.0]]))]
    with pytest.raises(PlannerError, match="stroke 0: a contact stroke needs a positive force"):
        periods_of(strokes, [np.array([2.0, 0.0])], start_m=np.zeros(3) + 0.05, standoff_m=0.03)


def _rk4(p: np.ndarray, v: np.ndarray, f: float, u: np.ndarray, df: float, h: float) -> np.ndarray:
    """Independent integration of the planner's model (numpy, fine steps)."""
    mu, m, g = PARAMS.wall_friction, PARAMS.mass_kg, np.array([0.0, -GRAVITY_MPS2, 0.0])

    def deriv(x: np.ndarray) -> np.ndarray:
        vv, ff = x[3:6], x[6]
        speed = np.sqrt(vv[0] ** 2 + vv[1] ** 2 + 0.03**2)
        alpha = np.array([-mu * vv[0] / speed, -mu * vv[1] / speed, 1.0])
        return np.concatenate([vv, (u + ff * alpha) / m + g, [df]])

    x = np.concatenate([p, v, [f]])
    for _ in range(10):
        k1 = deriv(x)
        k2 = deriv(x + h / 20 * k1)
        k3 = deriv(x + h / 20 * k2)
        k4 = deriv(x + h / 10 * k3)
        x = x + h / 60 * (k1 + 2 * k2 + 2 * k3 + k4)
    return x


@pytest.mark.slow
def test_planned_contact_period_obeys_dynamics_and_limits() -> None:
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.08, 0.0], [0.08, 0.06]]))]
    periods = periods_of(
        strokes, [np.array([2.0, 3.0, 2.5])], start_m=np.array([0.0, 0.0, 0.06]), standoff_m=0.03
    )
    limits = Limits()
    sol = solve_period(periods[1], PARAMS, limits)
    assert sol.status == "Solve_Succeeded"
    assert sol.iterations > 0 and 0.0 < sol.ipopt_s <= sol.solve_s
    h = np.diff(sol.t_s)
    assert np.all(h > 0.0) and np.all(h <= limits.h_max_s + 1e-6)
    for k in range(h.size):
        df = (sol.force_n[k + 1] - sol.force_n[k]) / h[k]
        x = _rk4(sol.p_m[k], sol.v_mps[k], sol.force_n[k], sol.control_n[k], df, h[k])
        assert x[0:3] == pytest.approx(sol.p_m[k + 1], abs=2e-4)
        assert x[3:6] == pytest.approx(sol.v_mps[k + 1], abs=2e-3)
    assert np.all(np.abs(sol.p_m[:, 2]) < 1e-6)
    assert np.linalg.norm(sol.v_mps, axis=1).max() <= limits.v_max_mps + 1e-4
    assert np.linalg.norm(sol.a_mps2, axis=1).max() <= limits.a_max_mps2 + 1e-4
    assert np.max(np.abs(np.diff(sol.force_n)) / h) <= limits.force_rate_max_nps + 1e-4
    # Waypoints are met: the stroke's corner at (0.08, 0) with 3 N.
    hit = np.argmin(np.linalg.norm(sol.p_m - [0.08, 0.0, 0.0], axis=1))
    assert sol.force_n[hit] == pytest.approx(3.0, abs=1e-5)


@pytest.mark.slow
def test_plan_reports_ipopt_and_keeps_limits() -> None:
    period_cache.SOLVED_PERIODS.clear()  # solved now, not reused from an earlier test's plan
    plan = plan_writing([StrokeInput(np.array([[0.0, 0.0], [0.1, 0.0]]))], SURFACE, PlanSettings())
    rep = plan.feasibility
    assert all(p["ipopt_status"] == "Solve_Succeeded" for p in rep["periods"])
    assert all(p["start"] == "cold" for p in rep["periods"]) and rep["periods_reused"] == 0
    assert rep["ipopt_iterations"] > 0 and 0.0 < rep["ipopt_solve_s"] <= rep["build_and_solve_s"]
    assert rep["peak_speed_mps"] <= 0.2 + 1e-3
    assert plan.force_n is not None and plan.width_m is not None
    assert plan.samples.pen_down.any()
    down = plan.samples.pen_down
    # Pen-down samples lie on the wall.
    assert np.abs(SURFACE.standoff_m(plan.samples.position_m_enu[down])).max() < 1e-6


def test_width_out_of_range_names_stroke_and_point() -> None:
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.1, 0.0]]), np.array([8e-3, 30e-3]))]
    with pytest.raises(PlannerError, match=r"field 'w', stroke 0, point 1: width 30.00 mm"):
        plan_writing(strokes, SURFACE, PlanSettings())


def test_wall_point_out_of_reach_is_refused() -> None:
    strokes = [StrokeInput(np.array([[0.0, 0.0], [2.5, 0.0]]))]
    with pytest.raises(PlannerError, match=r"stroke 0, point 1: .*beyond the reach"):
        plan_writing(strokes, SURFACE, PlanSettings())


def test_force_beyond_the_rotors_names_the_thrust_limit() -> None:
    weak = PlanSettings(params=HexarotorParams(thrust_max_n=6.6))
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.1, 0.0]]), np.array([14e-3, 14e-3]))]
    with pytest.raises(InfeasibleTrajectoryError, match=r"stroke 0: pressing 6\.00 N") as info:
        plan_writing(strokes, SURFACE, weak)
    assert info.value.limit == "thrust"
    assert re.search(r"needs a rotor thrust of (\d+\.\d\d) N, beyond the rotors' 0\.\.6\.60 N",
                     str(info.value))  # fmt: skip
    assert info.value.value is not None and info.value.value > 6.6


@pytest.mark.slow
def test_cached_solver_takes_each_periods_own_waypoints() -> None:
    """The solver of a step count is built once; a second period with the same count (its
    waypoints shifted along the wall) gets its own bounds: the same trajectory, shifted."""
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.08, 0.0], [0.08, 0.06]]))]
    forces = [np.array([2.0, 3.0, 2.5])]
    first = periods_of(strokes, forces, start_m=np.array([0.0, 0.0, 0.06]), standoff_m=0.03)[1]
    shift = np.array([0.3, -0.2, 0.0])
    moved = dataclasses.replace(first, points_m=first.points_m + shift)
    builds = solver_cache.period_solver.cache_info().misses
    a = solve_period(first, PARAMS, Limits())
    b = solve_period(moved, PARAMS, Limits())
    assert solver_cache.period_solver.cache_info().misses <= builds + 1
    assert b.p_m == pytest.approx(a.p_m + shift, abs=1e-6)
    assert b.force_n == pytest.approx(a.force_n, abs=1e-6)
    assert b.t_s == pytest.approx(a.t_s, abs=1e-6)


def _corner_stroke_periods() -> list[Period]:
    strokes = [StrokeInput(np.array([[0.0, 0.0], [0.08, 0.0], [0.08, 0.06]]))]
    forces = [np.array([2.0, 3.0, 2.5])]
    return periods_of(strokes, forces, start_m=np.array([0.0, 0.0, 0.06]), standoff_m=0.03)


def test_step_counts_round_up_to_the_ladder_and_spread_over_segments() -> None:
    assert [solver_cache.step_count(k) for k in (1, 8, 9, 12, 14, 40, 42)] == [
        8,
        8,
        9,
        12,
        15,
        41,
        45,
    ]
    needed = [3, 10, 2, 7]
    steps = solver_cache.spread_steps(needed, 25)
    assert sum(steps) == 25
    assert all(s >= k for s, k in zip(steps, needed, strict=True))
    assert steps == [4, 11, 2, 8]


@pytest.mark.slow
def test_periods_of_nearby_step_counts_share_one_solver() -> None:
    """A stroke a few steps longer than another is planned on the same built NLP."""
    corner = _corner_stroke_periods()[1]
    first, longer = (
        dataclasses.replace(corner, points_m=corner.points_m * [scale, scale, 1.0])
        for scale in (1.1, 1.2)
    )
    needs = [sum(steps.steps_per_segment(p, Limits())) for p in (first, longer)]
    assert needs[0] != needs[1]
    builds = solver_cache.period_solver.cache_info().misses
    a = solve_period(first, PARAMS, Limits())
    b = solve_period(longer, PARAMS, Limits())
    assert solver_cache.period_solver.cache_info().misses <= builds + 1
    assert a.t_s.size == b.t_s.size == solver_cache.step_count(max(needs)) + 1
    assert a.status == b.status == "Solve_Succeeded"


@pytest.mark.slow
def test_rotor_thrust_limit_holds_when_the_plan_without_it_exceeds_it() -> None:
    """The thrust rows are left out of the first solve; a plan beyond the rotors' range is
    solved again with them. 9 N rotors press 3 N while hovering (8.8 N) but the nominal plan
    of the corner stroke asks 9.2 N (the paper's eq. 7: in corridors it turns the corner
    slower)."""
    period = _corner_stroke_periods()[1]
    nominal = solve_period(period, PARAMS, PAPER)
    weak = HexarotorParams(thrust_max_n=9.0)
    assert _max_thrust_n(nominal, weak) > 9.1
    sol = solve_period(period, weak, PAPER)
    assert sol.status == "Solve_Succeeded"
    assert _max_thrust_n(sol, weak) <= 9.0 + 1e-5
    assert sol.iterations > nominal.iterations


def _max_thrust_n(sol: nlp.PeriodSolution, params: HexarotorParams) -> float:
    """Largest rotor thrust in [N] of the planned steps (allocation of
    ``contact_model.rotor_thrusts``)."""
    states = np.vstack([sol.p_m.T, sol.v_mps.T, sol.force_n])[:, :-1]
    actions = np.vstack([sol.control_n.T, np.zeros(sol.control_n.shape[0])])
    return float(np.asarray(solver_cache.thrust_function(params)(states, actions)).max())


@pytest.mark.slow
def test_time_steps_change_smoothly_and_save_iterations() -> None:
    """The cost of a time step's change from the step before keeps neighbouring steps within
    a few hundredths of a second (without it they jump between 0.02 and 0.19 s where the cost
    is flat) and saves IPOPT iterations for the same duration (within 1 %; the paper's eq. 7,
    where it was measured)."""
    for period in _corner_stroke_periods():
        smooth = solve_period(period, PARAMS, PAPER)
        free = solve_period(period, PARAMS, dataclasses.replace(PAPER, weight_dh=0.0))
        assert np.abs(np.diff(np.diff(smooth.t_s))).max() < 0.03
        assert smooth.iterations < free.iterations
        assert smooth.t_s[-1] == pytest.approx(free.t_s[-1], rel=0.01)


@pytest.mark.parametrize(
    "rows", [period_nlp.Rows(thrust=t, corridor=c) for t in (False, True) for c in (False, True)]
)
def test_period_nlp_derivatives_are_the_horizons_own(rows: period_nlp.Rows) -> None:
    """The gradient, Jacobian and Hessian scattered from one step's derivatives equal
    CasADi's derivatives of the whole horizon's cost and constraints (at a random point, with
    the first step's hover force, the time-step change cost between steps and the corridor's
    parabola rows)."""
    n = 5
    weights = nlp.cost_weights(Limits())
    problem, derivatives = period_nlp.period_nlp(n, rows, PARAMS, weights, 10.0)
    w, p, f, g = problem["x"], problem["p"], problem["f"], problem["g"]
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", g.numel())
    hessian = ca.triu(ca.hessian(lam_f * f + ca.dot(lam_g, g), w)[0])
    own = ca.Function("own", [w, p, lam_f, lam_g], [ca.gradient(f, w), ca.jacobian(g, w), hessian])
    rng = np.random.default_rng(1)
    point = (
        rng.standard_normal(w.numel()),
        rng.standard_normal(period_nlp.STEP_PARAMETERS * n),
        1.7,
        rng.standard_normal(g.numel()),
    )
    grad_own, jac_own, hess_own = (np.asarray(ca.densify(m)) for m in own(*point))
    grad = np.asarray(ca.densify(derivatives["grad_f"](*point[:2])[1]))
    jac = np.asarray(ca.densify(derivatives["jac_g"](*point[:2])[1]))
    hess = np.asarray(ca.densify(derivatives["hess_lag"](*point)))
    assert grad == pytest.approx(grad_own, abs=1e-9)
    assert jac == pytest.approx(jac_own, abs=1e-9)
    assert hess == pytest.approx(hess_own, abs=1e-9)
    assert np.abs(hess_own).max() > 1.0
