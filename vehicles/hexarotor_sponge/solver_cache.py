"""IPOPT solvers of the period NLP (paper eq. 7), built once per step count and kept, and the
step-count ladder that lets periods of nearby lengths share one built solver.

A solver is built per ``(steps, optional rows, params, cost weights)`` only (5-10 ms of CPU
whatever the step count, see ``period_nlp``); a period's waypoints, contact mode and limits reach
it as variable and constraint bounds (``nlp``), its force profile as a parameter.
"""

from __future__ import annotations

import math
import threading
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np

from vehicles.hexarotor_sponge.contact_model import rotor_thrusts
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.period_nlp import ACTION, STATE, Rows, period_nlp

STEP_COUNT_RATIO = 1.1
"""Ratio of consecutive step counts a period is planned with: a period's steps are rounded up to
the next count so periods of nearby lengths share one built solver (about 5 % more steps on
average; building a count costs 5-10 ms of CPU and about 1 MB, an iteration on 48 steps about
1 ms). Against 1.25 (about 12 % more steps) it cuts IPOPT's work (iterations times steps) on
the 1 m letters 永, R, &, O by 17, 18, 15, 24 % (8: +10 %), with 19 solvers built for the five
letters instead of 11."""
SMALLEST_STEP_COUNT = 8
"""Smallest count of the ladder (the shortest period, leaving the wall, needs 8 at 0.15 s)."""


def step_count(needed: int) -> int:
    """The smallest count of the ladder ``ceil(8 * STEP_COUNT_RATIO^k)`` that is at least
    ``needed``."""
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
1148, their durations within 0.1 %. The iteration cap is the solver's own
(:data:`MAX_ITERATIONS`, :data:`TRIAL_MAX_ITERATIONS`)."""

MAX_ITERATIONS = 600
"""IPOPT's iteration cap on a period's last (or only) attempt."""
TRIAL_MAX_ITERATIONS = 80
"""IPOPT's iteration cap on an attempt that has a retry with more steps after it (``nlp``'s
``RETRY_STEP_SCALES``). An attempt that fails runs to its cap (cursive:6's pieces: 150
iterations, 0.3-0.6 s of CPU each, at the earlier cap of 150), and its retry plans it in about
20. The most a solve that succeeded took on the 215 inputs of ``bench_wall_corpus.py`` is 64
(the 1 m P), most take under 30; 15 of the inputs have a first attempt that fails
(``steps.CORRIDOR_TRAVEL_SLACK``), all planned by their retries."""


@lru_cache(maxsize=64)
def period_solver(
    n: int,
    rows: Rows,
    params: HexarotorParams,
    weights: tuple[float, ...],
    weight_dh: float,
    max_iter: int = MAX_ITERATIONS,
) -> tuple[ca.Function, threading.Lock]:
    """IPOPT on the NLP of ``n`` RK4 steps with the optional ``rows`` (:func:`period_nlp`,
    options :data:`IPOPT_OPTIONS`), and the lock that keeps one solve (and its stats) at a time
    on it.

    ``weights``: the cost weights ``(v, u, du, force, time)`` of the planner's limits;
    ``weight_dh``: the cost per [s^2] of a time step's change from the step before;
    ``max_iter``: IPOPT's iteration cap.
    """
    nlp, derivatives = period_nlp(n, rows, params, weights, weight_dh)
    options: dict[str, Any] = {
        "print_time": False,
        "record_time": True,
        "ipopt": {**IPOPT_OPTIONS, "max_iter": max_iter},
        **derivatives,
    }
    return ca.nlpsol(f"period_{n}", "ipopt", nlp, options), threading.Lock()


@lru_cache(maxsize=4)
def thrust_function(params: HexarotorParams) -> ca.Function:
    """:func:`rotor_thrusts` as a function of a step's state and action (for screening a
    solution solved without the thrust rows)."""
    x = ca.SX.sym("x", STATE)
    u = ca.SX.sym("u", ACTION)
    return ca.Function("thrusts", [x, u], [rotor_thrusts(x, u, params)])
