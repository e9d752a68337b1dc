"""From a world acceleration command to inner-loop inputs (throttle, roll, pitch) via G_c.

Phang 2015 eq. 1-2: ``[thr, phi_c, theta_c]^T = G_c a_b`` with ``a_b`` the body-frame acceleration
command, written for a forward-right-down body. In our forward-left-up body the roll axis is the
same and the pitch axis is reversed, so ``roll = -0.1019 a_by`` and ``pitch = +0.1019 a_bx``
(0.1019 = 1/g: small-angle tilt). The throttle row acts on the upward specific thrust
``g + a_z``; dividing by ``cos(roll) cos(pitch)`` keeps the vertical component when tilted.
Only yaw rotates the command into the body frame (the yaw reference is generated separately).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]

G_C = np.array([[0.0, 0.0, 0.0334], [0.0, 0.1019, 0.0], [-0.1019, 0.0, 0.0]])
"""Eq. 2: body accelerations (forward-right-down) -> (throttle, roll, pitch)."""


@dataclass(frozen=True)
class InnerLoopSetpoint:
    """Inputs for the inner attitude loop of N vehicles."""

    throttle: FloatArray
    """Throttle in plant units (G_c row 1 times specific thrust), shape (N,)."""
    roll_rad: FloatArray
    """Roll about body x (forward-left-up) in [rad], shape (N,)."""
    pitch_rad: FloatArray
    """Pitch about body y (positive tilts the thrust towards +x) in [rad], shape (N,)."""
    yaw_rad: FloatArray
    """Heading in [rad], shape (N,)."""


def inner_setpoint(
    accel_cmd_mps2_enu: FloatArray,
    yaw_rad: FloatArray,
    *,
    gravity_mps2: float = 9.81,
    max_tilt_rad: float = 0.5,
    max_throttle: float = 0.6553,
    g_c: FloatArray = G_C,
) -> InnerLoopSetpoint:
    """Convert (N, 3) world acceleration commands to throttle, roll, pitch, yaw (clamped)."""
    cy, sy = np.cos(yaw_rad), np.sin(yaw_rad)
    ax, ay = accel_cmd_mps2_enu[:, 0], accel_cmd_mps2_enu[:, 1]
    forward = cy * ax + sy * ay
    right = sy * ax - cy * ay  # body -y (left) is +right in forward-right-down
    up = gravity_mps2 + accel_cmd_mps2_enu[:, 2]
    roll = np.minimum(np.maximum(float(g_c[1, 1]) * right, -max_tilt_rad), max_tilt_rad)
    pitch = np.minimum(np.maximum(-float(g_c[2, 0]) * forward, -max_tilt_rad), max_tilt_rad)
    throttle = (float(g_c[0, 2]) * up) / (np.cos(roll) * np.cos(pitch))
    throttle = np.minimum(np.maximum(throttle, 0.0), max_throttle)
    return InnerLoopSetpoint(throttle, roll, pitch, yaw_rad)
