"""IPOPT solvers of the period NLP (paper eq. 7), built once per step count and kept, and the
step-count ladder that lets periods of nearby lengths share one built solver.

Building a solver (CasADi expansion, exact derivatives) takes longer than solving with it, so a
solver is built per ``(steps, thrust rows, params, cost weights)`` only; a period's waypoints,
contact mode and limits reach it as variable and constraint bounds (``nlp``), its force profile
as a parameter.
"""

from __future__ import annotations

import math
import threading
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from vehicles.hexarotor_sponge.contact_model import hover_control_n, rk4_step, rotor_thrusts
from vehicles.hexarotor_sponge.params import HexarotorParams

STATE = 7
"""State of a node: position (3), velocity (3), normal force."""
ACTION = 4
"""Action of a step: control force f_a (3), force rate dF/dt."""
NODE = STATE + ACTION + 1
"""Decision variables of one step in the NLP's vector: x_k, u_k, h_k (the last node only x_N)."""

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


IPOPT_OPTIONS: dict[str, Any] = {
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
}
"""From a start that nearly keeps the dynamics the default adaptive barrier spends 20-30
iterations at mu 0.1; a monotone barrier from 1e-2 with a first Hessian perturbation of 1e-2
(the friction direction's curvature at low speed makes the Hessian indefinite early) and tol
1e-4 (dynamics and limits still to 1e-6) takes the six bench glyphs from 2831 iterations to
1148, their durations within 0.1 %."""


@lru_cache(maxsize=64)
def period_solver(
    n: int,
    thrust_rows: bool,
    params: HexarotorParams,
    weights: tuple[float, ...],
    weight_dh: float,
) -> tuple[ca.Function, threading.Lock]:
    """IPOPT on the NLP of ``n`` RK4 steps (:func:`_period_nlp`, options
    :data:`IPOPT_OPTIONS`), and the lock that keeps one solve (and its stats) at a time on it.

    ``weights``: the cost weights ``(v, u, du, force, time)`` of the planner's limits;
    ``weight_dh``: the cost per [s^2] of a time step's change from the step before.
    """
    options: dict[str, Any] = {"print_time": False, "record_time": True, "ipopt": IPOPT_OPTIONS}
    nlp = _period_nlp(n, thrust_rows, params, weights, weight_dh)
    return ca.nlpsol(f"period_{n}", "ipopt", nlp, options), threading.Lock()


def _period_nlp(
    n: int,
    thrust_rows: bool,
    params: HexarotorParams,
    weights: tuple[float, ...],
    weight_dh: float,
) -> dict[str, Any]:
    """The NLP of ``n`` RK4 steps in SX (derivatives exact and evaluated without CasADi's MX
    overhead).

    Variables: ``[x_0, u_0, h_0, ..., x_{n-1}, u_{n-1}, h_{n-1}, x_n]``; parameter: the wanted
    force at nodes ``0..n-1``; constraints per step: the RK4 defect (7), ``|a|^2`` (1), rotor
    thrusts (6, only with ``thrust_rows``) and ``|v|^2`` (1). The cost adds ``weight_dh`` times
    the squared change of each time step from the one before.
    """
    stage = _stage_function(thrust_rows, params, weights)
    w = ca.SX.sym("w", NODE * n + STATE)
    force_ref = ca.SX.sym("force_ref", n)
    hover = hover_control_n(params)
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
        if k > 0:
            cost += weight_dh * (w[at + NODE - 1] - w[at - 1]) ** 2
        constraints += [defect, path]
    return {"x": w, "p": force_ref, "f": cost, "g": ca.vertcat(*constraints)}


def _stage_function(
    thrust_rows: bool, params: HexarotorParams, weights: tuple[float, ...]
) -> ca.Function:
    """One step ``k``: (x_k, u_k, h_k, f_a of step k-1, x_{k+1}, wanted force) -> (RK4 defect,
    cost of the step, path constraints ``[|a_k|^2, thrusts (6), |v_k|^2]``)."""
    x = ca.SX.sym("x", STATE)
    u = ca.SX.sym("u", ACTION)
    h = ca.SX.sym("h")
    u_prev = ca.SX.sym("u_prev", 3)
    x_next = ca.SX.sym("x_next", STATE)
    force_ref = ca.SX.sym("force_ref")
    x_end, rate = rk4_step(x, u, h, params)
    defect = x_next - x_end
    stage = stage_cost(x, u, u_prev, force_ref, params, weights)
    thrusts = rotor_thrusts(x, u, params) if thrust_rows else ca.SX(0, 1)
    path = ca.vertcat(ca.sumsqr(rate[3:6]), thrusts, ca.sumsqr(x[3:6]))
    return ca.Function("stage", [x, u, h, u_prev, x_next, force_ref], [defect, stage * h, path])


def stage_cost(
    x: Any,
    u: Any,
    u_prev: Any,
    force_ref: Any,
    params: HexarotorParams,
    weights: tuple[float, ...],
) -> Any:
    """Cost per second of one step (eq. 7a with the force and control terms): speed, control
    force from hover and from the step before, force from the wanted force, and time."""
    weight_v, weight_u, weight_du, weight_force, time_weight = weights
    return (
        weight_v * ca.sumsqr(x[3:6])
        + weight_u * ca.sumsqr(u[0:3] - hover_control_n(params))
        + weight_du * ca.sumsqr(u[0:3] - u_prev)
        + weight_force * (x[6] - force_ref) ** 2
        + time_weight
    )


@lru_cache(maxsize=4)
def thrust_function(params: HexarotorParams) -> ca.Function:
    """:func:`rotor_thrusts` as a function of a step's state and action (for screening a
    solution solved without the thrust rows)."""
    x = ca.SX.sym("x", STATE)
    u = ca.SX.sym("u", ACTION)
    return ca.Function("thrusts", [x, u], [rotor_thrusts(x, u, params)])
