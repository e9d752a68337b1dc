"""Small rotations: a rotation vector to its matrix, and the vector of a skew matrix."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


def rotation_of(rotvec_rad: FloatArray) -> FloatArray:
    """Rotation matrix (3, 3) of a rotation vector in [rad] (Rodrigues)."""
    angle = float(np.linalg.norm(rotvec_rad))
    if angle < 1e-12:
        return np.eye(3)
    k = rotvec_rad / angle
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.asarray(np.eye(3) + math.sin(angle) * kx + (1.0 - math.cos(angle)) * kx @ kx)


def vee(skew: FloatArray) -> FloatArray:
    """The vector (3,) of a skew-symmetric matrix (3, 3)."""
    return np.array([skew[2, 1], skew[0, 2], skew[1, 0]])
