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

This module fits one period to the NLP: its step counts, bounds, start, thrust screening and
result; the model is in ``contact_model``, the built solvers and step-count ladder in
``solver_cache``, the error of a period without a trajectory in ``diagnosis``.
"""

from __future__ import annotations

import dataclasses
import enum
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from planner.errors import PlannerError
from vehicles.hexarotor_sponge.contact_model import acceleration_mps2, contact_direction
from vehicles.hexarotor_sponge.corridor import SHORTEST_CHORD_M, chords, corridor_rows
from vehicles.hexarotor_sponge.diagnosis import Iterate, infeasible_error
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.period_nlp import ACTION, NODE, STATE, Rows
from vehicles.hexarotor_sponge.solver_cache import (
    MAX_ITERATIONS,
    TRIAL_MAX_ITERATIONS,
    period_solver,
    thrust_function,
)
from vehicles.hexarotor_sponge.steps import steps_per_segment, waypoint_nodes
from vehicles.hexarotor_sponge.waypoints import Period

FloatArray = NDArray[np.float64]


class PeriodStart(enum.Enum):
    """Where a period's trajectory came from, for the plan's report."""

    COLD = "cold"
    """IPOPT from the paper's start (linear states, their control forces, equal steps)."""
    REUSED = "reused"
    """The trajectory of an identical period (in its own frame) solved earlier in this process
    (``period_cache``): no IPOPT now; status, iterations and times are that solve's."""


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
    start: PeriodStart = PeriodStart.COLD
    """Solved now from the paper's start, or reused from an identical period."""

    def moved(self, offset_m: FloatArray) -> PeriodSolution:
        """The same trajectory with its positions moved by ``offset_m`` (3,) in [m], wall
        coordinates (the period NLP does not depend on where on the wall it is)."""
        return dataclasses.replace(self, p_m=self.p_m + offset_m)


def own_frame_origin_m(period: Period) -> FloatArray:
    """The origin (3,) in [m], wall coordinates, of ``period``'s own frame: its first waypoint
    along the wall (x, y), the wall itself (s = 0)."""
    return np.array([period.points_m[0, 0], period.points_m[0, 1], 0.0])


OWN_FRAME_DECIMALS = 9
"""Decimals in [m] a period's waypoints in its own frame are rounded to (a nanometre): the
same shape anywhere on the wall then gives the same NLP to the bit (``0.39 - 0.31`` is not
``0.08``)."""


def in_own_frame(period: Period) -> Period:
    """``period`` with its waypoints in its own frame (:func:`own_frame_origin_m`), rounded to
    :data:`OWN_FRAME_DECIMALS`."""
    local = np.round(period.points_m - own_frame_origin_m(period), OWN_FRAME_DECIMALS)
    sagitta = None if period.sagitta_m is None else np.round(period.sagitta_m, OWN_FRAME_DECIMALS)
    return dataclasses.replace(period, points_m=local, sagitta_m=sagitta)


def solve_period(period: Period, params: HexarotorParams, limits: Limits) -> PeriodSolution:
    """Optimise one period from rest at its first waypoint to rest at its last.

    Solved in the period's own frame (:func:`solve_own_frame`) and moved back onto the wall, so
    two periods of the same shape anywhere on the wall get the same trajectory bit for bit
    (what ``period_cache`` relies on)."""
    return solve_own_frame(in_own_frame(period), period, params, limits).moved(
        own_frame_origin_m(period)
    )


RETRY_STEP_SCALES = (0.75, 0.5)
"""In corridors (``Limits.corridor_m``), a period IPOPT found no trajectory for is solved again
with its steps allotted at these shares of ``h_init`` (a third more steps, then twice as many):
a near-stop in a corridor, where the pen turns sharply at the end of a piece, can leave IPOPT
wandering for its iterations on the first count (the 1 m cursive run: one piece of 57 steps
ran out of 600, at 0.75 h_init it plans in 19 iterations), so an attempt with a retry after it
stops at ``solver_cache.TRIAL_MAX_ITERATIONS``."""


def solve_own_frame(
    local: Period, period: Period, params: HexarotorParams, limits: Limits
) -> PeriodSolution:
    """Optimise ``local`` (``period`` in its own frame, see :func:`in_own_frame`); positions of
    the result in that frame. ``period`` names the waypoints on the wall in an error. In
    corridors, a period without a trajectory is tried again with more steps
    (:data:`RETRY_STEP_SCALES`, all but the last attempt capped at
    :data:`~vehicles.hexarotor_sponge.solver_cache.TRIAL_MAX_ITERATIONS`); the error is that of
    the first count's."""
    attempts = [limits]
    if limits.corridor_m is not None:
        attempts += [
            dataclasses.replace(limits, h_init_s=scale * limits.h_init_s)
            for scale in RETRY_STEP_SCALES
        ]
    first: PlannerError | None = None
    for i, attempt in enumerate(attempts):
        cap = TRIAL_MAX_ITERATIONS if i < len(attempts) - 1 else MAX_ITERATIONS
        try:
            return _solve_steps(local, period, params, attempt, cap)
        except PlannerError as err:  # IPOPT found no trajectory (``diagnosis``)
            first = first or err
    assert first is not None
    raise first


def force_rows(period: Period, nodes: NDArray[np.int_], *, corridor: bool) -> FloatArray:
    """(n, 2) wanted force per node ``0..n-1``: with corridors on a contact period, its chord
    start's force and the change to the chord's end (``period_nlp.wanted_force`` reads how far
    along the chord the node is); else, and on chords too short to say (the press and the lift
    in place at a stroke's ends), the force interpolated by step index (the paper's) and 0."""
    n = int(nodes[-1])
    by_step = np.column_stack([np.interp(np.arange(n), nodes, period.force_n), np.zeros(n)])
    if not (corridor and period.contact):
        return by_step
    length, _ = chords(period.points_m[:, 0:2])
    segment = np.repeat(np.arange(nodes.size - 1), np.diff(nodes))
    start = period.force_n[segment]
    along = np.column_stack([start, period.force_n[segment + 1] - start])
    return np.where((length[segment] >= SHORTEST_CHORD_M)[:, None], along, by_step)


def _solve_steps(
    local: Period,
    period: Period,
    params: HexarotorParams,
    limits: Limits,
    max_iter: int,
) -> PeriodSolution:
    """:func:`solve_own_frame` with the steps allotted at ``limits.h_init_s``, the first solve
    capped at ``max_iter`` IPOPT iterations.

    The NLP of ``n`` steps is built once per ``(n, params, cost weights)`` (see
    :func:`period_solver`); the period's waypoints, contact mode and limits enter as variable and
    constraint bounds, its force profile as a parameter. The rotor thrust limits are screened:
    the NLP without them is solved first (the thrust rows are three quarters of the inequality
    constraints and the nominal letters never reach them; without them an iteration costs about
    a quarter less), and only a solution with a rotor beyond its range is solved again with them
    (from the same start: warm-started from the first solution, primal or primal and dual, the
    eight such periods of the six bench glyphs with 10 N rotors took 194 to 310 iterations
    against 168).
    """
    needed = steps_per_segment(local, limits)
    nodes = waypoint_nodes(needed)
    n = int(nodes[-1])
    forces = force_rows(local, nodes, corridor=limits.corridor_m is not None)
    corridor, lower, upper = corridor_rows(local, nodes, limits.corridor_m)
    lbx, ubx = _variable_bounds(local, nodes, limits)
    guess = initial_guess(local, nodes, limits.h_init_s * sum(needed) / n, params)
    started = time.perf_counter()
    step_parameters = np.column_stack([forces, corridor]).ravel(order="F")
    problem = _Problem(guess, step_parameters, lbx, ubx, lower, upper)
    w, stats, iterations, ipopt_s = _solve(n, False, problem, params, limits, max_iter)
    xs, us, hs = unpack(w, n)
    if _thrust_margin_n(xs, us, params) < -THRUST_SLACK_N:
        w, stats, more, more_s = _solve(n, True, problem, params, limits, MAX_ITERATIONS)
        iterations, ipopt_s = iterations + more, ipopt_s + more_s
        xs, us, hs = unpack(w, n)
    solve_s = time.perf_counter() - started
    status = str(stats.get("return_status", "unknown"))
    if not bool(stats.get("success", False)):
        on_wall = xs.copy()
        on_wall[0:3] += own_frame_origin_m(period)[:, None]
        raise infeasible_error(period, nodes, status, Iterate(on_wall, us, hs), params, limits)
    return period_solution(xs, us, hs, status, iterations, (solve_s, ipopt_s), params)


THRUST_SLACK_N = 1e-6
"""Rotor thrust in [N] a solution without the thrust rows may be beyond the rotors' range by."""


@dataclass(frozen=True)
class _Problem:
    """One period's data for a built solver."""

    guess: FloatArray
    """IPOPT's start."""
    step_parameters: FloatArray
    """Wanted forces (n,), then the corridors' parameters (n, 7), column by column."""
    lbx: FloatArray
    ubx: FloatArray
    corridor_lower: FloatArray
    """(n, 2) lower bounds in [m] of the nodes across and along their chords."""
    corridor_upper: FloatArray


def _solve(
    n: int,
    thrust_rows: bool,
    problem: _Problem,
    params: HexarotorParams,
    limits: Limits,
    max_iter: int,
) -> tuple[FloatArray, dict[str, Any], int, float]:
    """IPOPT, stopping after ``max_iter`` iterations, on the NLP of ``n`` steps from
    ``problem``: its variables, statistics, iterations and own wall-clock seconds."""
    rows = Rows(thrust=thrust_rows, corridor=limits.corridor_m is not None)
    lbg, ubg = _constraint_bounds(n, rows, problem, params, limits)
    solver, lock = period_solver(n, rows, params, cost_weights(limits), limits.weight_dh, max_iter)
    with lock:
        out = solver(
            x0=problem.guess,
            p=problem.step_parameters,
            lbx=problem.lbx,
            ubx=problem.ubx,
            lbg=lbg,
            ubg=ubg,
        )
        stats = solver.stats()
    iterations = int(stats.get("iter_count", -1))
    return np.asarray(out["x"]).ravel(), stats, iterations, float(stats.get("t_wall_total", 0.0))


def _thrust_margin_n(xs: FloatArray, us: FloatArray, params: HexarotorParams) -> float:
    """Smallest distance in [N] of a rotor's thrust inside ``[0, thrust_max]`` over the steps
    (negative: beyond)."""
    thrusts = np.asarray(thrust_function(params)(xs[:, :-1], us))
    return float(min(thrusts.min(), params.thrust_max_n - thrusts.max()))


def cost_weights(limits: Limits) -> tuple[float, ...]:
    """The cost weights of ``limits``: the only limits that shape the NLP's expressions."""
    return (
        limits.weight_v,
        limits.weight_u,
        limits.weight_du,
        limits.weight_force,
        limits.time_weight,
    )


def _constraint_bounds(
    n: int, rows: Rows, problem: _Problem, params: HexarotorParams, limits: Limits
) -> tuple[FloatArray, FloatArray]:
    """Bounds of the per-step constraints of :func:`period_solver` (the limits of eq. 7g, and
    the corridor's with its rows)."""
    rotors = 6 if rows.thrust else 0
    lower = np.concatenate([np.zeros(STATE), [-np.inf], np.zeros(rotors), [-np.inf]])
    upper = np.concatenate(
        [
            np.zeros(STATE),
            [limits.a_max_mps2**2],
            np.full(rotors, params.thrust_max_n),
            [limits.v_max_mps**2],
        ]
    )
    lbg, ubg = np.tile(lower, (n, 1)), np.tile(upper, (n, 1))
    if rows.corridor:
        lbg = np.column_stack([lbg, problem.corridor_lower])
        ubg = np.column_stack([ubg, problem.corridor_upper])
    return lbg.ravel(), ubg.ravel()


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


def linear_states(
    period: Period, nodes: NDArray[np.int_], h_s: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The paper's start of the states: positions (n+1, 3) and normal forces (n+1,) linear
    between the waypoints at ``nodes``, velocities (n+1, 3) in [m/s] their central differences
    over steps of ``h_s`` in [s], at rest at both ends."""
    k = np.arange(int(nodes[-1]) + 1)
    p0 = np.column_stack([np.interp(k, nodes, period.points_m[:, j]) for j in range(3)])
    f0 = np.interp(k, nodes, period.force_n)
    v0 = np.gradient(p0, axis=0) / h_s
    v0[0] = v0[-1] = 0.0
    return p0, v0, f0


def initial_guess(
    period: Period, nodes: NDArray[np.int_], h_s: float, params: HexarotorParams
) -> FloatArray:
    """The paper's start (equal steps of ``h_s`` in [s], states linear between waypoints) with
    the control force that flies those states instead of hover thrust: the finite-difference
    acceleration less gravity and the contact force. A start that nearly keeps the dynamics
    saves IPOPT about a quarter of its iterations (letters A, I, R: 1454 -> 1082) for the same
    optimum."""
    n = int(nodes[-1])
    p0, v0, f0 = linear_states(period, nodes, h_s)
    a0 = np.diff(v0, axis=0) / h_s
    gravity = np.array([0.0, -GRAVITY_MPS2, 0.0])
    contact = f0[:-1, None] * contact_direction(v0[:-1], params.wall_friction)
    guess = np.zeros((n + 1, NODE))
    guess[:, 0:3], guess[:, 3:6], guess[:, 6] = p0, v0, f0
    guess[:n, STATE : STATE + 3] = params.mass_kg * (a0 - gravity) - contact
    guess[:n, STATE + 3] = np.diff(f0) / h_s
    guess[:, NODE - 1] = h_s
    return guess.ravel()[: NODE * n + STATE]


def unpack(w: FloatArray, n: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """States (7, n+1), actions (4, n) and time steps (n,) from the NLP's variable vector."""
    full = np.concatenate([w, np.zeros(NODE - STATE)]).reshape(n + 1, NODE)
    return full[:, :STATE].T.copy(), full[:n, STATE : STATE + ACTION].T.copy(), full[:n, -1].copy()


def period_solution(
    xs: FloatArray,
    us: FloatArray,
    hs: FloatArray,
    status: str,
    iterations: int,
    timing: tuple[float, float],
    params: HexarotorParams,
) -> PeriodSolution:
    """The :class:`PeriodSolution` of states (7, n+1), actions (4, n) and steps (n,) in [s]
    however they were solved (cached NLP or the benchmark's peer), with the accelerations of
    the model at the nodes (the last node's: 0); ``timing``: (build and solve, IPOPT's own) [s]."""
    t = np.concatenate([[0.0], np.cumsum(hs)])
    v = xs[3:6].T
    force = xs[6]
    acc = np.vstack([acceleration_mps2(v[:-1], force[:-1], us[0:3].T, params), np.zeros(3)])
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
