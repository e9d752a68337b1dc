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

import time
from dataclasses import dataclass
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
    h_init_s: float = 0.1
    """Initial time step in [s] (paper: 0.1 s)."""
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


def steps_per_segment(period: Period, limits: Limits) -> list[int]:
    """Steps between consecutive waypoints, in proportion to distance and force change."""
    d = np.linalg.norm(np.diff(period.points_m, axis=0), axis=1)
    df = np.abs(np.diff(period.force_n))
    travel_s = np.maximum(d / limits.v_max_mps, np.sqrt(d / limits.a_max_mps2))
    travel_s[[0, -1]] = np.maximum(travel_s[[0, -1]], 2.0 * np.sqrt(d[[0, -1]] / limits.a_max_mps2))
    by_dist = np.ceil(1.3 * travel_s / limits.h_init_s)
    by_force = np.ceil(df / (limits.force_rate_max_nps * limits.h_init_s)) + 1
    return [int(max(2, a, b)) for a, b in zip(by_dist, by_force, strict=True)]


def solve_period(period: Period, params: HexarotorParams, limits: Limits) -> PeriodSolution:
    """Optimise one period from rest at its first waypoint to rest at its last."""
    steps = steps_per_segment(period, limits)
    nodes = np.concatenate([[0], np.cumsum(steps)]).astype(int)
    n = int(nodes[-1])
    opti = ca.Opti()
    x = opti.variable(7, n + 1)
    u = opti.variable(4, n)
    h = opti.variable(n)
    m = params.mass_kg
    g = ca.DM([0.0, -GRAVITY_MPS2, 0.0])
    mu = params.wall_friction

    def f(xs: Any, us: Any) -> Any:
        acc = (us[0:3] + xs[6] * alpha(xs[3:6], mu)) / m + g
        return ca.vertcat(xs[3:6], acc, us[3])

    cost: Any = 0
    force_path = np.interp(np.arange(n + 1), nodes, period.force_n)
    hover = ca.DM([0.0, m * GRAVITY_MPS2, 0.0])
    for k in range(n):
        xk, uk, hk = x[:, k], u[:, k], h[k]
        k1 = f(xk, uk)
        k2 = f(xk + hk / 2 * k1, uk)
        k3 = f(xk + hk / 2 * k2, uk)
        k4 = f(xk + hk * k3, uk)
        opti.subject_to(x[:, k + 1] == xk + hk / 6 * (k1 + 2 * k2 + 2 * k3 + k4))
        du = uk[0:3] - (u[0:3, k - 1] if k > 0 else hover)
        stage = (
            limits.weight_v * ca.sumsqr(xk[3:6])
            + limits.weight_u * ca.sumsqr(uk[0:3] - hover)
            + limits.weight_du * ca.sumsqr(du)
            + limits.weight_force * (xk[6] - force_path[k]) ** 2
            + limits.time_weight
        )
        cost += stage * hk
        opti.subject_to(ca.sumsqr(k1[3:6]) <= limits.a_max_mps2**2)
        _thrust_limits(opti, xk, uk, params)
    opti.minimize(cost)
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
    _initial_guess(opti, x, u, h, period, nodes, limits, m)
    opti.solver(
        "ipopt",
        {"print_time": False, "expand": True, "record_time": True},
        {
            "print_level": 0,
            "sb": "yes",
            "max_iter": 600,
            "tol": 1e-6,
            "acceptable_tol": 1e-4,
            "mu_strategy": "adaptive",
        },
    )
    started = time.perf_counter()
    try:
        sol = opti.solve()
        values = sol.value
    except RuntimeError:
        values = opti.debug.value
    solve_s = time.perf_counter() - started
    stats = opti.stats()
    status = str(stats.get("return_status", "unknown"))
    xs = np.asarray(values(x)).reshape(7, n + 1)
    us = np.asarray(values(u)).reshape(4, n)
    hs = np.asarray(values(h)).reshape(n)
    if not bool(stats.get("success", False)):
        _raise_infeasible(period, status, xs, hs, limits)
    timing = (solve_s, float(stats.get("t_wall_total", solve_s)))
    return _solution(xs, us, hs, status, int(stats.get("iter_count", -1)), timing, params)


def _thrust_limits(opti: Any, xk: Any, uk: Any, params: HexarotorParams) -> None:
    """0 <= thrusts <= max for the wrench that applies ``f_a`` and cancels the gravity moment of
    the offset centre of mass and the contact force's moment (allocation about the body origin)."""
    rot = ca.DM(BODY_IN_WALL)
    inverse = ca.DM(np.linalg.inv(wrench_matrix(params)))
    com = ca.DM(params.com_m_body)
    tip = ca.DM(params.tip_m_body)
    force_body = rot.T @ uk[0:3]
    weight_body = rot.T @ ca.DM([0.0, -params.mass_kg * GRAVITY_MPS2, 0.0])
    contact_body = rot.T @ (xk[6] * alpha(xk[3:6], params.wall_friction))
    torque = -ca.cross(com, weight_body) - ca.cross(tip, contact_body)
    thrust = inverse @ ca.vertcat(force_body, torque)
    opti.subject_to(opti.bounded(0.0, thrust, params.thrust_max_n))


def _initial_guess(
    opti: Any,
    x: Any,
    u: Any,
    h: Any,
    period: Period,
    nodes: FloatArray,
    limits: Limits,
    mass_kg: float,
) -> None:
    """The paper's start: 0.1 s steps, states linear between waypoints, hover thrust."""
    n = int(nodes[-1])
    k = np.arange(n + 1)
    p0 = np.column_stack([np.interp(k, nodes, period.points_m[:, j]) for j in range(3)])
    f0 = np.interp(k, nodes, period.force_n)
    v0 = np.gradient(p0, axis=0) / limits.h_init_s
    v0[0] = v0[-1] = 0.0
    opti.set_initial(x, np.vstack([p0.T, v0.T, f0]))
    rate = np.diff(f0) / limits.h_init_s
    hover = np.tile([[0.0], [mass_kg * GRAVITY_MPS2], [0.0]], (1, n))
    opti.set_initial(u, np.vstack([hover, rate]))
    opti.set_initial(h, np.full(n, limits.h_init_s))


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
    speed = np.sqrt(v[:-1, 0] ** 2 + v[:-1, 1] ** 2 + SLIDE_EPS_MPS**2)
    mu = params.wall_friction
    contact = np.column_stack([-mu * v[:-1, 0] / speed, -mu * v[:-1, 1] / speed, np.ones(len(hs))])
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
