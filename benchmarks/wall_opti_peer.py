"""The wall planner's eq. 7 built the plain way: the peer of
``vehicles.hexarotor_sponge.nlp.solve_period`` in ``bench_wall.py``.

The same problem as the planner's, term for term: the planner's own ``rk4_step``, ``stage_cost``,
``rotor_thrusts`` and corridor rows (``corridor_terms``), the same steps (its step counts on the
ladder, ``h_init``), the same time-step change cost (``weight_dh``), the same start and IPOPT's
same options; only built as the planner was before its solvers were cached: a new
``casadi.Opti`` with ``expand`` for every period, so every period pays for building the MX graph
in Python, expanding it to SX and deriving it, and every bound is a constraint row. (Before issue
33 the peer solved another problem, 0.1 s steps and no step-change cost, so its speed ratio mixed
the problem with the implementation.) The rotor thrust rows are always in (the planner screens
them out when no rotor reaches its range).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.contact_model import hover_control_n, rk4_step, rotor_thrusts
from vehicles.hexarotor_sponge.corridor import corridor_rows
from vehicles.hexarotor_sponge.diagnosis import Iterate, infeasible_error
from vehicles.hexarotor_sponge.limits import Limits
from vehicles.hexarotor_sponge.nlp import (
    PeriodSolution,
    cost_weights,
    force_rows,
    initial_guess,
    period_solution,
    unpack,
)
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.period_nlp import (
    NODE,
    STATE,
    corridor_terms,
    stage_cost,
    wanted_force,
)
from vehicles.hexarotor_sponge.solver_cache import IPOPT_OPTIONS, MAX_ITERATIONS
from vehicles.hexarotor_sponge.steps import steps_per_segment, waypoint_nodes
from vehicles.hexarotor_sponge.waypoints import Period

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class _Variables:
    """The decision variables of one period of ``n`` steps in a ``casadi.Opti``."""

    x: Any
    """(7, n+1) states: position (3), velocity (3), normal force."""
    u: Any
    """(4, n) actions: control force f_a (3), force rate dF/dt."""
    h: Any
    """(n,) time steps in [s]."""


def solve_period_opti(period: Period, params: HexarotorParams, limits: Limits) -> PeriodSolution:
    """The planner's period NLP in a fresh ``casadi.Opti`` (expanded), every bound a
    constraint, from the planner's start."""
    needed = steps_per_segment(period, limits)
    nodes = waypoint_nodes(needed)
    n = int(nodes[-1])
    opti = ca.Opti()
    var = _Variables(opti.variable(7, n + 1), opti.variable(4, n), opti.variable(n))
    forces = force_rows(period, nodes, corridor=limits.corridor_m is not None)
    rows, _, _ = corridor_rows(period, nodes, limits.corridor_m)
    wanted = [wanted_force(var.x[0:2, k], ca.DM(forces[k]), ca.DM(rows[k])) for k in range(n)]
    opti.minimize(_dynamics_and_cost(opti, var, wanted, params, limits))
    _bounds(opti, var, period, nodes, limits)
    _corridor(opti, var, period, nodes, limits)
    guess = initial_guess(period, nodes, limits.h_init_s * sum(needed) / n, params)
    xs, us, hs = unpack(guess, n)
    opti.set_initial(var.x, xs)
    opti.set_initial(var.u, us)
    opti.set_initial(var.h, hs)
    opti.solver(
        "ipopt",
        {"print_time": False, "expand": True, "record_time": True},
        {**IPOPT_OPTIONS, "max_iter": MAX_ITERATIONS},
    )
    started = time.perf_counter()
    try:
        values = opti.solve().value
    except RuntimeError:
        values = opti.debug.value
    solve_s = time.perf_counter() - started
    stats = opti.stats()
    status = str(stats.get("return_status", "unknown"))
    xs = np.asarray(values(var.x)).reshape(STATE, n + 1)
    us = np.asarray(values(var.u)).reshape(NODE - STATE - 1, n)
    hs = np.asarray(values(var.h)).reshape(n)
    if not bool(stats.get("success", False)):
        raise infeasible_error(period, nodes, status, Iterate(xs, us, hs), params, limits)
    timing = (solve_s, float(stats.get("t_wall_total", solve_s)))
    return period_solution(xs, us, hs, status, int(stats.get("iter_count", -1)), timing, params)


def _dynamics_and_cost(
    opti: Any, var: _Variables, wanted: list[Any], params: HexarotorParams, limits: Limits
) -> Any:
    """Per step: the RK4 defect, acceleration and rotor thrust constraints; returns the cost
    (the planner's own dynamics, stage cost and time-step change cost)."""
    x, u, h = var.x, var.u, var.h
    weights = cost_weights(limits)
    hover = hover_control_n(params)
    cost: Any = 0
    for k in range(h.shape[0]):  # n steps
        xk, uk, hk = x[:, k], u[:, k], h[k]
        x_end, rate = rk4_step(xk, uk, hk, params)
        opti.subject_to(x[:, k + 1] == x_end)
        u_prev = u[0:3, k - 1] if k > 0 else hover
        cost += stage_cost(xk, uk, u_prev, wanted[k], params, weights) * hk
        if k > 0:
            cost += limits.weight_dh * (hk - h[k - 1]) ** 2
        opti.subject_to(ca.sumsqr(rate[3:6]) <= limits.a_max_mps2**2)
        opti.subject_to(opti.bounded(0.0, rotor_thrusts(xk, uk, params), params.thrust_max_n))
    return cost


def _bounds(
    opti: Any, var: _Variables, period: Period, nodes: NDArray[np.int_], limits: Limits
) -> None:
    """Time steps (7c), force rate and speed (7g), rest at both ends, the waypoints (7d) and the
    contact mode (7e), each as a constraint (the planner's variable bounds)."""
    x, u, h = var.x, var.u, var.h
    n = int(nodes[-1])
    opti.subject_to(opti.bounded(0.02, h, limits.h_max_s))
    rate = limits.force_rate_max_nps if period.contact else 0.0
    opti.subject_to(opti.bounded(-rate, u[3, :], rate))
    for k in range(n):
        opti.subject_to(ca.sumsqr(x[3:6, k]) <= limits.v_max_mps**2)
    opti.subject_to(x[3:6, 0] == 0)
    opti.subject_to(x[3:6, n] == 0)
    for i, node in enumerate(nodes):
        opti.subject_to(x[0:3, int(node)] == period.points_m[i])
        opti.subject_to(x[6, int(node)] == period.force_n[i])
    if period.contact:
        opti.subject_to(x[2, :] == 0)
        opti.subject_to(x[6, :] >= 0)
    else:
        opti.subject_to(x[2, :] >= 0)
        opti.subject_to(x[6, :] == 0)


def _corridor(
    opti: Any, var: _Variables, period: Period, nodes: NDArray[np.int_], limits: Limits
) -> None:
    """The planner's corridor rows at the nodes of a contact period (none in free flight or
    in the paper's eq. 7)."""
    rows, lower, upper = corridor_rows(period, nodes, limits.corridor_m)
    for k in np.flatnonzero(np.isfinite(lower[:, 0])):
        terms = corridor_terms(var.x[0:2, int(k)], ca.DM(rows[k]))
        opti.subject_to(opti.bounded(lower[k], terms, upper[k]))
