"""The writing point's contact and rotor model on the wall, shared by the period NLP (``nlp``),
its cached solvers (``solver_cache``) and the benchmark's fresh-Opti peer.

Wall coordinates ``(x, y, s)``: x along the wall, y up, s out of the wall. The contact wrench is
``F alpha(v)`` with ``alpha = n - mu v_t / |v_t|`` (paper eq. 4 and 6: Coulomb friction against
the sliding direction, smoothed near 0 m/s). Rotor thrusts follow from the allocation matrix,
including the torque that cancels the friction force's moment about the centre of mass.
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
