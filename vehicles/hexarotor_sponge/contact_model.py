"""The writing point's dynamics, contact and rotor model on the wall, shared by the period NLP
(``nlp``), its cached solvers (``solver_cache``) and the benchmark's fresh-Opti peer.

Wall coordinates ``(x, y, s)``: x along the wall, y up, s out of the wall. The contact wrench is
``F alpha(v)`` with ``alpha = n - mu v_t / |v_t|`` (paper eq. 4 and 6: Coulomb friction against
the sliding direction, smoothed near 0 m/s). Rotor thrusts follow from the allocation matrix,
including the torque that cancels the friction force's moment about the centre of mass. A state
``x`` is position (3), velocity (3) and normal force; an action ``u`` the control force ``f_a``
(3, wall axes) and the force rate; the functions take CasADi SX or MX alike.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.allocation import wrench_matrix
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams

FloatArray = NDArray[np.float64]

BODY_IN_WALL = np.array([[0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])
"""Columns: body x (into the wall), body y, body z (up) in wall coordinates (x, y, s)."""
SLIDE_EPS_MPS = 0.03
"""Speed in [m/s] below which the friction direction is smoothed to 0."""


def alpha(v: Any, mu: float) -> Any:
    """Contact wrench direction per unit normal force (force part), wall coordinates."""
    speed = ca.sqrt(v[0] ** 2 + v[1] ** 2 + SLIDE_EPS_MPS**2)
    return ca.vertcat(-mu * v[0] / speed, -mu * v[1] / speed, 1.0)


def contact_direction(v_mps: FloatArray, mu: float) -> FloatArray:
    """:func:`alpha` in numpy for (N, 3) velocities: (N, 3) contact force per unit normal force."""
    speed = np.sqrt(v_mps[:, 0] ** 2 + v_mps[:, 1] ** 2 + SLIDE_EPS_MPS**2)
    friction = -mu * v_mps[:, 0:2] / speed[:, None]
    return np.column_stack([friction, np.ones(len(speed))])


def acceleration_mps2(
    v_mps: FloatArray, force_n: FloatArray, control_n: FloatArray, params: HexarotorParams
) -> FloatArray:
    """:func:`point_rate`'s acceleration in numpy: (N, 3) in [m/s^2] at (N, 3) velocities,
    (N,) normal forces in [N] and (N, 3) control forces in [N]."""
    contact = force_n[:, None] * contact_direction(v_mps, params.wall_friction)
    gravity = np.array([0.0, -GRAVITY_MPS2, 0.0])
    return np.asarray((control_n + contact) / params.mass_kg + gravity)


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


def rk4_step(x: Any, u: Any, h: Any, params: HexarotorParams) -> tuple[Any, Any]:
    """The state after a step of ``h`` in [s] from ``x`` under the action ``u`` (classic RK4 of
    :func:`point_rate`), and the rate at its start (its acceleration is limited)."""
    k1 = point_rate(x, u, params)
    k2 = point_rate(x + h / 2 * k1, u, params)
    k3 = point_rate(x + h / 2 * k2, u, params)
    k4 = point_rate(x + h * k3, u, params)
    return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), k1


def point_rate(x: Any, u: Any, params: HexarotorParams) -> Any:
    """d/dt of the writing point's state (eq. 7b): velocity, acceleration from the control
    force, the contact force and gravity in [m/s^2], and the force rate."""
    gravity = ca.DM([0.0, -GRAVITY_MPS2, 0.0])
    acc = (u[0:3] + x[6] * alpha(x[3:6], params.wall_friction)) / params.mass_kg + gravity
    return ca.vertcat(x[3:6], acc, u[3])


def hover_control_n(params: HexarotorParams) -> ca.DM:
    """The control force f_a in [N], wall coordinates, that holds the vehicle's weight."""
    return ca.DM([0.0, params.mass_kg * GRAVITY_MPS2, 0.0])
