"""The wall planner's eq. 7 as it was solved before the cached solvers: the peer of
``vehicles.hexarotor_sponge.nlp.solve_period`` in ``bench_wall.py``.

Same model, cost and constraints (the planner's own ``rk4_step``, ``stage_cost`` and
``rotor_thrusts``, so the two cannot drift apart), with the IPOPT options, steps and step counts
of then (adaptive barrier, 0.1 s steps, no rounding of the count); a new ``casadi.Opti`` with
``expand`` is built for every period, so every period pays for building the MX graph in Python,
expanding it to SX and deriving it.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.contact_model import hover_control_n, rk4_step, rotor_thrusts
from vehicles.hexarotor_sponge.diagnosis import Iterate, infeasible_error
from vehicles.hexarotor_sponge.nlp import (
    Limits,
    PeriodSolution,
    cost_weights,
    linear_states,
    period_solution,
    steps_per_segment,
)
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.period_nlp import stage_cost
from vehicles.hexarotor_sponge.waypoints import Period

FloatArray = NDArray[np.float64]

PAPER_STEP_S = 0.1
"""The paper's step in [s], which the planner allocated steps at before it took 0.15 s."""


IPOPT_OPTIONS: dict[str, Any] = {
    "print_level": 0,
    "sb": "yes",
    "max_iter": 600,
    "tol": 1e-6,
    "acceptable_tol": 1e-4,
    "mu_strategy": "adaptive",
}
"""IPOPT's options of then: the adaptive barrier and tol 1e-6."""


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
    """The planner before the cached solvers: a fresh ``casadi.Opti`` (expanded) per period,
    every bound as a constraint, the paper's hover-thrust start from its 0.1 s steps."""
    limits = dataclasses.replace(limits, h_init_s=PAPER_STEP_S)
    steps = steps_per_segment(period, limits)
    nodes = np.concatenate([[0], np.cumsum(steps)]).astype(int)
    n = int(nodes[-1])
    opti = ca.Opti()
    var = _Variables(opti.variable(7, n + 1), opti.variable(4, n), opti.variable(n))
    force_path = np.interp(np.arange(n + 1), nodes, period.force_n)
    opti.minimize(_dynamics_and_cost(opti, var, force_path, params, limits))
    _bounds(opti, var, period, nodes, limits)
    _initial_guess(opti, var, period, nodes, limits, params.mass_kg)
    opti.solver("ipopt", {"print_time": False, "expand": True, "record_time": True}, IPOPT_OPTIONS)
    started = time.perf_counter()
    try:
        values = opti.solve().value
    except RuntimeError:
        values = opti.debug.value
    solve_s = time.perf_counter() - started
    stats = opti.stats()
    status = str(stats.get("return_status", "unknown"))
    xs = np.asarray(values(var.x)).reshape(7, n + 1)
    us = np.asarray(values(var.u)).reshape(4, n)
    hs = np.asarray(values(var.h)).reshape(n)
    if not bool(stats.get("success", False)):
        raise infeasible_error(period, nodes, status, Iterate(xs, us, hs), params, limits)
    timing = (solve_s, float(stats.get("t_wall_total", solve_s)))
    return period_solution(xs, us, hs, status, int(stats.get("iter_count", -1)), timing, params)


def _dynamics_and_cost(
    opti: Any, var: _Variables, force_path: FloatArray, params: HexarotorParams, limits: Limits
) -> Any:
    """Per step: the RK4 defect, acceleration and rotor thrust constraints; returns the cost
    (the planner's own dynamics and stage cost)."""
    x, u, h = var.x, var.u, var.h
    weights = cost_weights(limits)
    hover = hover_control_n(params)
    cost: Any = 0
    for k in range(h.shape[0]):  # n steps
        xk, uk, hk = x[:, k], u[:, k], h[k]
        x_end, rate = rk4_step(xk, uk, hk, params)
        opti.subject_to(x[:, k + 1] == x_end)
        u_prev = u[0:3, k - 1] if k > 0 else hover
        cost += stage_cost(xk, uk, u_prev, force_path[k], params, weights) * hk
        opti.subject_to(ca.sumsqr(rate[3:6]) <= limits.a_max_mps2**2)
        _thrust_limits(opti, xk, uk, params)
    return cost


def _bounds(
    opti: Any, var: _Variables, period: Period, nodes: NDArray[np.int_], limits: Limits
) -> None:
    """Time steps (7c), force rate and speed (7g), rest at both ends, the waypoints (7d) and the
    contact mode (7e), each as a constraint."""
    x, u, h = var.x, var.u, var.h
    n = int(nodes[-1])
    opti.subject_to(opti.bounded(0.02, h, limits.h_max_s))
    opti.subject_to(opti.bounded(-limits.force_rate_max_nps, u[3, :], limits.force_rate_max_nps))
    for k in range(n + 1):
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
        opti.subject_to(u[3, :] == 0)


def _thrust_limits(opti: Any, xk: Any, uk: Any, params: HexarotorParams) -> None:
    """0 <= each rotor's thrust <= its maximum (the planner's own allocation)."""
    opti.subject_to(opti.bounded(0.0, rotor_thrusts(xk, uk, params), params.thrust_max_n))


def _initial_guess(
    opti: Any,
    var: _Variables,
    period: Period,
    nodes: NDArray[np.int_],
    limits: Limits,
    mass_kg: float,
) -> None:
    """The paper's start: 0.1 s steps, states linear between waypoints, hover thrust."""
    n = int(nodes[-1])
    p0, v0, f0 = linear_states(period, nodes, limits.h_init_s)
    opti.set_initial(var.x, np.vstack([p0.T, v0.T, f0]))
    rate = np.diff(f0) / limits.h_init_s
    hover = np.tile([[0.0], [mass_kg * GRAVITY_MPS2], [0.0]], (1, n))
    opti.set_initial(var.u, np.vstack([hover, rate]))
    opti.set_initial(var.h, np.full(n, limits.h_init_s))
