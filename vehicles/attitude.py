"""A body's attitude as the bus and Foxglove carry it: a unit quaternion (x, y, z, w) turning the
body's forward-left-up axes into the world's east-north-up ones (pure numerics).

Each room turns its own representation into it (the brush quadrotor's Z-Y-X Euler angles, a
MuJoCo body's rotation matrix) for the agent's telemetry.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]
QuaternionXyzw = tuple[float, float, float, float]
"""A unit quaternion (x, y, z, w), body FLU -> world ENU."""


def quaternions_of_euler(attitude_rad: ArrayLike) -> FloatArray:
    """(N, 4) quaternions (x, y, z, w) of Z-Y-X Euler angles (roll, pitch, yaw) in [rad], (N, 3):
    the rotation ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    half = 0.5 * np.asarray(attitude_rad, dtype=np.float64).reshape(-1, 3)
    cr, cp, cy = np.cos(half).T
    sr, sp, sy = np.sin(half).T
    return np.stack(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ],
        axis=-1,
    )


def quaternion_of_matrix(rotation: ArrayLike) -> QuaternionXyzw:
    """The quaternion (x, y, z, w) of a rotation matrix (3, 3), with ``w >= 0``: Shepperd's
    method, from the largest of the four squared components (stable for every rotation)."""
    r = np.asarray(rotation, dtype=np.float64).reshape(3, 3)
    trace = r[0, 0] + r[1, 1] + r[2, 2]
    squares = (trace, r[0, 0], r[1, 1], r[2, 2])
    k = int(np.argmax(squares))
    if k == 0:
        s = 2.0 * np.sqrt(1.0 + trace)  # s = 4 w
        q = ((r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s, s / 4)
    elif k == 1:
        s = 2.0 * np.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])  # s = 4 x
        q = (s / 4, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s, (r[2, 1] - r[1, 2]) / s)
    elif k == 2:
        s = 2.0 * np.sqrt(1.0 - r[0, 0] + r[1, 1] - r[2, 2])  # s = 4 y
        q = ((r[0, 1] + r[1, 0]) / s, s / 4, (r[1, 2] + r[2, 1]) / s, (r[0, 2] - r[2, 0]) / s)
    else:
        s = 2.0 * np.sqrt(1.0 - r[0, 0] - r[1, 1] + r[2, 2])  # s = 4 z
        q = ((r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, s / 4, (r[1, 0] - r[0, 1]) / s)
    sign = -1.0 if q[3] < 0 else 1.0
    x, y, z, w = (sign * float(c) for c in q)
    return (x, y, z, w)


def quaternion_of_wxyz(wxyz: ArrayLike) -> QuaternionXyzw:
    """A quaternion stored scalar first (MuJoCo's ``xquat``, MAVLink's) as (x, y, z, w)."""
    w, x, y, z = (float(c) for c in np.asarray(wxyz, dtype=np.float64).reshape(4))
    return (x, y, z, w)
