"""Contact-aware motion-force trajectory optimisation of one period (paper eq. 7) in CasADi/IPOPT.

Wall coordinates ``(x, y, s)``: x along the wall, y up, s out of the wall (``phi``). The vehicle
keeps its attitude facing the wall (eq. 7f, ``g(x) = 0``), so the state of the writing point is
``q = p`` (3), ``v`` (3) and the normal force ``F``; the actions are the control force ``f_a``
(3, wall axes) and the force rate ``dF/dt``; the time steps ``h_n`` are variables too. The contact
wrench is ``F alpha(v)`` with ``alpha = n - mu v_t / |v_t|`` (eq. 4 and 6: Coulomb friction
against the sliding direction; the sign of each tangential axis is replaced by the component of
the unit sliding direction, smoothed near 0 m/s, which is MuJoCo's isotropic cone and eq. 6 for
axis-aligned motion). Rotor thrust limits are imposed through the allocation matrix, including
the torque that cancels the friction force's moment about the centre of mass.
"""

from __future__ import annotations

import math
import threading
import time
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from planner.errors import InfeasibleTrajectoryError
from vehicles.hexarotor_sponge.allocation import wrench_matrix
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.waypoints import Period

FloatArray = NDArray[np.float64]

BODY_IN_WALL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
"""Columns: body x (into the wall), body y, body z (up) in wall coordinates (x, y, s)."""
SLIDE_EPS_MPS = 0.03
"""Speed in [m/s] below which the friction direction is smoothed to 0."""


@dataclass(frozen=True)
class Limits:
    """Planner limits and weights (paper's defaults)."""

    v_max_mps: float = 0.20
    """Largest speed of the writing point in [m/s]."""
    a_max_mps2: float = 0.20
    """Largest acceleration in [m/s^2]."""
    force_rate_max_nps: float = 2.0
    """Largest |dF/dt| in [N/s]."""
    h_init_s: float = 0.15
    """Time step in [s] the steps are allocated at and IPOPT starts from (paper: 0.1 s; its
    bound ``h_max_s`` allows 0.2 s). 0.15 s plans letters A, I, R and three Chinese characters
    with a third fewer steps and IPOPT iterations than 0.1 s, their durations within 0.6 %;
    0.2 s leaves no slack under ``h_max_s`` and a stroke's force ramp is found infeasible."""
    h_max_s: float = 0.2
    """Upper bound of a time step in [s] (eq. 7c)."""
    weight_v: float = 1.0
    """Cost weight of |v|^2 in [1/(m/s)^2 s] (eq. 7a)."""
    weight_u: float = 1e-3
    """Cost weight of the control force's change from hover, per [N^2 s]."""
    weight_du: float = 1e-2
    """Cost weight of the control force's change between steps, per [N^2 s]."""
    time_weight: float = 1.0
    """gamma: cost per second of writing (eq. 7a)."""
    weight_force: float = 20.0
    """Cost weight per [N^2 s] of the force's departure from the waypoint forces interpolated
    along the stroke (an addition to eq. 7a: the wanted width holds between waypoints too)."""


@dataclass(frozen=True)
class PeriodSolution:
    """The optimised nodes of one period and IPOPT's account of it."""

    t_s: FloatArray
    """(N+1,) node times from the period's start in [s]."""
    p_m: FloatArray
    """(N+1, 3) positions, wall coordinates."""
    v_mps: FloatArray
    """(N+1, 3) velocities."""
    a_mps2: FloatArray
    """(N+1, 3) accelerations (last node: 0)."""
    force_n: FloatArray
    """(N+1,) normal force."""
    control_n: FloatArray
    """(N, 3) control force f_a in wall coordinates."""
    status: str
    """IPOPT's return status."""
    iterations: int
    """IPOPT iterations."""
    solve_s: float
    """Wall-clock time in [s] of building the solver (CasADi expansion, derivatives) and solving."""
    ipopt_s: float
    """IPOPT's own wall-clock time in [s] (CasADi's ``t_wall_total``)."""


def alpha(v: Any, mu: float) -> Any:
    """Contact wrench direction per unit normal force (force part), wall coordinates."""
    speed = ca.sqrt(v[0] ** 2 + v[1] ** 2 + SLIDE_EPS_MPS**2)
    return ca.vertcat(-mu * v[0] / speed, -mu * v[1] / speed, 1.0)


def contact_direction(v_mps: FloatArray, mu: float) -> FloatArray:
    """:func:`alpha` in numpy for (N, 3) velocities: (N, 3) contact force per unit normal force."""
    speed = np.sqrt(v_mps[:, 0] ** 2 + v_mps[:, 1] ** 2 + SLIDE_EPS_MPS**2)
    friction = -mu * v_mps[:, 0:2] / speed[:, None]
    return np.column_stack([friction, np.ones(len(speed))])


def steps_per_segment(period: Period, limits: Limits) -> list[int]:
    """Steps between consecutive waypoints, in proportion to distance and force change."""
    d = np.linalg.norm(np.diff(period.points_m, axis=0), axis=1)
    df = np.abs(np.diff(period.force_n))
    travel_s = np.maximum(d / limits.v_max_mps, np.sqrt(d / limits.a_max_mps2))
    travel_s[[0, -1]] = np.maximum(travel_s[[0, -1]], 2.0 * np.sqrt(d[[0, -1]] / limits.a_max_mps2))
    by_dist = np.ceil(1.3 * travel_s / limits.h_init_s)
    by_force = np.ceil(df / (limits.force_rate_max_nps * limits.h_init_s)) + 1
    return [int(max(2, a, b)) for a, b in zip(by_dist, by_force, strict=True)]


STEP_COUNT_RATIO = 1.25
"""Ratio of consecutive step counts a period is planned with: a period's steps are rounded up to
the next count so periods of nearby lengths share one built solver (about 12 % more steps on
average; building costs about 6 ms of CPU per step, solving 3 ms per iteration)."""
SMALLEST_STEP_COUNT = 8
"""Smallest count of the ladder (the shortest period, leaving the wall, needs 8 at 0.15 s)."""


def step_count(needed: int) -> int:
    """The smallest count of the ladder ``ceil(8 * 1.25^k)`` that is at least ``needed``."""
    count = SMALLEST_STEP_COUNT
    k = 0
    while count < needed:
        k += 1
        count = math.ceil(SMALLEST_STEP_COUNT * STEP_COUNT_RATIO**k)
    return count


def spread_steps(needed: list[int], total: int) -> list[int]:
    """``total`` steps over the segments, each at least its ``needed`` count, the extra steps
    shared in proportion to the needed ones (largest remainders first)."""
    extra = total - sum(needed)
    share = np.asarray(needed, dtype=np.float64) * extra / sum(needed)
    whole = np.floor(share).astype(int)
    order = np.argsort(whole - share, kind="stable")
    whole[order[: extra - int(whole.sum())]] += 1
    return [a + int(b) for a, b in zip(needed, whole, strict=True)]


STATE = 7
"""State of a node: position (3), velocity (3), normal force."""
ACTION = 4
"""Action of a step: control force f_a (3), force rate dF/dt."""
NODE = STATE + ACTION + 1
"""Decision variables of one step in the NLP's vector: x_k, u_k, h_k (the last node only x_N)."""


def solve_period(period: Period, params: HexarotorParams, limits: Limits) -> PeriodSolution:
    """Optimise one period from rest at its first waypoint to rest at its last.

    The NLP of ``n`` steps is built once per ``(n, params, cost weights)`` (see
    :func:`_solver`); the period's waypoints, contact mode and limits enter as variable and
    constraint bounds, its force profile as a parameter. The rotor thrust limits are screened:
    the NLP without them is solved first (the thrust rows are three quarters of the inequality
    constraints and the nominal letters never reach them; without them an iteration costs about
    a quarter less), and only a solution with a rotor beyond its range is solved again with them.
    """
    needed = steps_per_segment(period, limits)
    steps = spread_steps(needed, step_count(sum(needed)))
    nodes = np.concatenate([[0], np.cumsum(steps)]).astype(int)
    n = int(nodes[-1])
    force_path = np.interp(np.arange(n), nodes, period.force_n)
    lbx, ubx = _variable_bounds(period, nodes, limits)
    guess = _initial_guess(period, nodes, limits.h_init_s * sum(needed) / n, params)
    started = time.perf_counter()
    problem = (guess, force_path, lbx, ubx)
    w, stats, iterations, ipopt_s = _solve(n, False, problem, params, limits)
    xs, us, hs = _unpack(w, n)
    if _thrust_margin_n(xs, us, params) < -THRUST_SLACK_N:
        w, stats, more, more_s = _solve(n, True, problem, params, limits)
        iterations, ipopt_s = iterations + more, ipopt_s + more_s
        xs, us, hs = _unpack(w, n)
    solve_s = time.perf_counter() - started
    status = str(stats.get("return_status", "unknown"))
    if not bool(stats.get("success", False)):
        _raise_infeasible(period, status, xs, hs, limits)
    return _solution(xs, us, hs, status, iterations, (solve_s, ipopt_s), params)


THRUST_SLACK_N = 1e-6
"""Rotor thrust in [N] a solution without the thrust rows may be beyond the rotors' range by."""


def _solve(
    n: int,
    thrust_rows: bool,
    problem: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    params: HexarotorParams,
    limits: Limits,
) -> tuple[FloatArray, dict[str, Any], int, float]:
    """IPOPT on the NLP of ``n`` steps from ``problem`` (start, wanted forces, variable
    bounds): its variables, statistics, iterations and own wall-clock seconds."""
    guess, force_path, lbx, ubx = problem
    lbg, ubg = _constraint_bounds(n, thrust_rows, params, limits)
    solver, lock = _solver(n, thrust_rows, params, _weights(limits))
    with lock:
        out = solver(x0=guess, p=force_path, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
        stats = solver.stats()
    iterations = int(stats.get("iter_count", -1))
    return np.asarray(out["x"]).ravel(), stats, iterations, float(stats.get("t_wall_total", 0.0))


def _thrust_margin_n(xs: FloatArray, us: FloatArray, params: HexarotorParams) -> float:
    """Smallest distance in [N] of a rotor's thrust inside ``[0, thrust_max]`` over the steps
    (negative: beyond)."""
    thrusts = np.asarray(_thrust_function(params)(xs[:, :-1], us))
    return float(min(thrusts.min(), params.thrust_max_n - thrusts.max()))


@lru_cache(maxsize=4)
def _thrust_function(params: HexarotorParams) -> ca.Function:
    """:func:`rotor_thrusts` as a function of a step's state and action."""
    x = ca.SX.sym("x", STATE)
    u = ca.SX.sym("u", ACTION)
    return ca.Function("thrusts", [x, u], [rotor_thrusts(x, u, params)])


def _weights(limits: Limits) -> tuple[float, ...]:
    """The cost weights of ``limits``: the only limits that shape the NLP's expressions."""
    return (
        limits.weight_v,
        limits.weight_u,
        limits.weight_du,
        limits.weight_force,
        limits.time_weight,
    )


@lru_cache(maxsize=64)
def _solver(
    n: int, thrust_rows: bool, params: HexarotorParams, weights: tuple[float, ...]
) -> tuple[ca.Function, threading.Lock]:
    """IPOPT on the NLP of ``n`` RK4 steps, and the lock that keeps one solve (and its stats)
    at a time on it.

    Variables: ``[x_0, u_0, h_0, ..., x_{n-1}, u_{n-1}, h_{n-1}, x_n]``; parameter: the wanted
    force at nodes ``0..n-1``; constraints per step: the RK4 defect (7), ``|a|^2`` (1), rotor
    thrusts (6, only with ``thrust_rows``) and ``|v|^2`` (1). Built in SX, so derivatives are
    exact and evaluated without CasADi's MX overhead; cached because building takes longer than
    solving.

    IPOPT's options: from a start that nearly keeps the dynamics the default adaptive barrier
    spends 20-30 iterations at mu 0.1; a monotone barrier from 1e-2 with a first Hessian
    perturbation of 1e-2 (the friction direction's curvature at low speed makes the Hessian
    indefinite early) and tol 1e-4 (dynamics and limits still to 1e-6) takes the six bench
    glyphs from 2831 iterations to 1148, their durations within 0.1 %.
    """
    stage = _stage_function(thrust_rows, params, weights)
    w = ca.SX.sym("w", NODE * n + STATE)
    force_ref = ca.SX.sym("force_ref", n)
    hover = ca.DM([0.0, params.mass_kg * GRAVITY_MPS2, 0.0])
    cost: Any = 0
    constraints = []
    for k in range(n):
        at = NODE * k
        u_prev = w[at - NODE + STATE : at - NODE + STATE + 3] if k > 0 else hover
        defect, stage_cost, path = stage(
            w[at : at + STATE],
            w[at + STATE : at + STATE + ACTION],
            w[at + NODE - 1],
            u_prev,
            w[at + NODE : at + NODE + STATE],
            force_ref[k],
        )
        cost += stage_cost
        constraints += [defect, path]
    nlp = {"x": w, "p": force_ref, "f": cost, "g": ca.vertcat(*constraints)}
    options: dict[str, Any] = {
        "print_time": False,
        "record_time": True,
        "ipopt": {
            "print_level": 0,
            "sb": "yes",
            "max_iter": 600,
            "tol": 1e-4,
            "constr_viol_tol": 1e-6,
            "acceptable_tol": 1e-4,
            "mu_strategy": "monotone",
            "mu_init": 1e-2,
            "first_hessian_perturbation": 1e-2,
            "perturb_inc_fact_first": 10.0,
        },
    }
    return ca.nlpsol(f"period_{n}", "ipopt", nlp, options), threading.Lock()


def _stage_function(
    thrust_rows: bool, params: HexarotorParams, weights: tuple[float, ...]
) -> ca.Function:
    """One step ``k``: (x_k, u_k, h_k, f_a of step k-1, x_{k+1}, wanted force) -> (RK4 defect,
    cost of the step, path constraints ``[|a_k|^2, thrusts (6), |v_k|^2]``)."""
    weight_v, weight_u, weight_du, weight_force, time_weight = weights
    x = ca.SX.sym("x", STATE)
    u = ca.SX.sym("u", ACTION)
    h = ca.SX.sym("h")
    u_prev = ca.SX.sym("u_prev", 3)
    x_next = ca.SX.sym("x_next", STATE)
    force_ref = ca.SX.sym("force_ref")
    m = params.mass_kg
    g = ca.DM([0.0, -GRAVITY_MPS2, 0.0])
    hover = ca.DM([0.0, m * GRAVITY_MPS2, 0.0])

    def f(xs: Any) -> Any:
        acc = (u[0:3] + xs[6] * alpha(xs[3:6], params.wall_friction)) / m + g
        return ca.vertcat(xs[3:6], acc, u[3])

    k1 = f(x)
    k2 = f(x + h / 2 * k1)
    k3 = f(x + h / 2 * k2)
    k4 = f(x + h * k3)
    defect = x_next - (x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
    stage = (
        weight_v * ca.sumsqr(x[3:6])
        + weight_u * ca.sumsqr(u[0:3] - hover)
        + weight_du * ca.sumsqr(u[0:3] - u_prev)
        + weight_force * (x[6] - force_ref) ** 2
        + time_weight
    )
    thrusts = rotor_thrusts(x, u, params) if thrust_rows else ca.SX(0, 1)
    path = ca.vertcat(ca.sumsqr(k1[3:6]), thrusts, ca.sumsqr(x[3:6]))
    return ca.Function("stage", [x, u, h, u_prev, x_next, force_ref], [defect, stage * h, path])


def rotor_thrusts(x: Any, u: Any, params: HexarotorParams) -> Any:
    """Rotor thrusts for the wrench that applies ``f_a`` and cancels the gravity moment of the
    offset centre of mass and the contact force's moment (allocation about the body origin)."""
    rot = ca.DM(BODY_IN_WALL)
    inverse = ca.DM(np.linalg.inv(wrench_matrix(params)))
    com = ca.DM(params.com_m_body)
    tip = ca.DM(params.tip_m_body)
    force_body = rot.T @ u[0:3]
    weight_body = rot.T @ ca.DM([0.0, -params.mass_kg * GRAVITY_MPS2, 0.0])
    contact_body = rot.T @ (x[6] * alpha(x[3:6], params.wall_friction))
    torque = -ca.cross(com, weight_body) - ca.cross(tip, contact_body)
    return inverse @ ca.vertcat(force_body, torque)


def _constraint_bounds(
    n: int, thrust_rows: bool, params: HexarotorParams, limits: Limits
) -> tuple[FloatArray, FloatArray]:
    """Bounds of the per-step constraints of :func:`_solver` (the limits of eq. 7g)."""
    rotors = 6 if thrust_rows else 0
    lower = np.concatenate([np.zeros(STATE), [-np.inf], np.zeros(rotors), [-np.inf]])
    upper = np.concatenate(
        [
            np.zeros(STATE),
            [limits.a_max_mps2**2],
            np.full(rotors, params.thrust_max_n),
            [limits.v_max_mps**2],
        ]
    )
    return np.tile(lower, n), np.tile(upper, n)


def _variable_bounds(
    period: Period, nodes: NDArray[np.int_], limits: Limits
) -> tuple[FloatArray, FloatArray]:
    """Bounds of the variables: time steps (7c), force rate (7g), rest at both ends, the
    waypoints (7d) and the contact mode (7e); IPOPT takes variables with equal bounds as fixed."""
    n = int(nodes[-1])
    lower = np.full((n + 1, NODE), -np.inf)
    upper = np.full((n + 1, NODE), np.inf)
    lower[:, NODE - 1], upper[:, NODE - 1] = 0.02, limits.h_max_s
    rate = limits.force_rate_max_nps if period.contact else 0.0
    lower[:, STATE + 3], upper[:, STATE + 3] = -rate, rate
    lower[[0, -1], 3:6] = upper[[0, -1], 3:6] = 0.0
    if period.contact:
        lower[:, 2] = upper[:, 2] = 0.0
        lower[:, 6] = 0.0
    else:
        lower[:, 2] = 0.0
        lower[:, 6] = upper[:, 6] = 0.0
    lower[nodes, 0:3] = upper[nodes, 0:3] = period.points_m
    lower[nodes, 6] = upper[nodes, 6] = period.force_n
    size = NODE * n + STATE
    return lower.ravel()[:size], upper.ravel()[:size]


def _initial_guess(
    period: Period, nodes: NDArray[np.int_], h_s: float, params: HexarotorParams
) -> FloatArray:
    """The paper's start (equal steps of ``h_s`` in [s], states linear between waypoints) with
    the control force that flies those states instead of hover thrust: the finite-difference
    acceleration less gravity and the contact force. A start that nearly keeps the dynamics
    saves IPOPT about a quarter of its iterations (letters A, I, R: 1454 -> 1082) for the same
    optimum."""
    n = int(nodes[-1])
    k = np.arange(n + 1)
    p0 = np.column_stack([np.interp(k, nodes, period.points_m[:, j]) for j in range(3)])
    f0 = np.interp(k, nodes, period.force_n)
    v0 = np.gradient(p0, axis=0) / h_s
    v0[0] = v0[-1] = 0.0
    a0 = np.diff(v0, axis=0) / h_s
    gravity = np.array([0.0, -GRAVITY_MPS2, 0.0])
    contact = f0[:-1, None] * contact_direction(v0[:-1], params.wall_friction)
    guess = np.zeros((n + 1, NODE))
    guess[:, 0:3], guess[:, 3:6], guess[:, 6] = p0, v0, f0
    guess[:n, STATE : STATE + 3] = params.mass_kg * (a0 - gravity) - contact
    guess[:n, STATE + 3] = np.diff(f0) / h_s
    guess[:, NODE - 1] = h_s
    return guess.ravel()[: NODE * n + STATE]


def _unpack(w: FloatArray, n: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """States (7, n+1), actions (4, n) and time steps (n,) from the NLP's variable vector."""
    full = np.concatenate([w, np.zeros(NODE - STATE)]).reshape(n + 1, NODE)
    return full[:, :STATE].T.copy(), full[:n, STATE : STATE + ACTION].T.copy(), full[:n, -1].copy()


def _raise_infeasible(
    period: Period, status: str, xs: FloatArray, hs: FloatArray, limits: Limits
) -> None:
    """A :class:`InfeasibleTrajectoryError` naming the period and the limit most exceeded."""
    t = np.concatenate([[0.0], np.cumsum(hs)])
    speed = np.linalg.norm(xs[3:6], axis=0)
    rate = np.abs(np.diff(xs[6])) / np.maximum(hs, 1e-9)
    ratios = {
        "v_max": (speed, limits.v_max_mps, t),
        "force_rate": (rate, limits.force_rate_max_nps, t[:-1]),
    }
    name, (vals, bound, times) = max(
        ratios.items(), key=lambda kv: float(kv[1][0].max()) / kv[1][1]
    )
    i = int(np.argmax(vals))
    raise InfeasibleTrajectoryError(
        f"{period.label}: IPOPT found no trajectory ({status}); worst limit {name}: "
        f"{float(vals[i]):.3g} against {bound:.3g}",
        limit=name,
        axis=None,
        t_s=float(times[i]),
        value=float(vals[i]),
        bound=bound,
    )


def _solution(
    xs: FloatArray,
    us: FloatArray,
    hs: FloatArray,
    status: str,
    iterations: int,
    timing: tuple[float, float],
    params: HexarotorParams,
) -> PeriodSolution:
    t = np.concatenate([[0.0], np.cumsum(hs)])
    v = xs[3:6].T
    force = xs[6]
    contact = contact_direction(v[:-1], params.wall_friction)
    gravity = np.array([0.0, -GRAVITY_MPS2, 0.0])
    acc = (us[0:3].T + force[:-1, None] * contact) / params.mass_kg + gravity
    acc = np.vstack([acc, np.zeros(3)])
    return PeriodSolution(
        t,
        xs[0:3].T.copy(),
        v.copy(),
        acc,
        force.copy(),
        us[0:3].T.copy(),
        status,
        iterations,
        timing[0],
        timing[1],
    )
