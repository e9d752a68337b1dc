"""Control allocation of the tilted-rotor hexarotor: a 6-D body wrench to six rotor thrusts.

Rotor ``i`` sits at angle ``60 i`` deg in the body plane, its thrust axis tilted about the rotor
arm by ``+-tilt`` (alternating), spinning in alternating directions. The thrust -> wrench map is a
constant invertible 6x6 matrix; within limits the allocation is its exact inverse, outside them a
bounded least-squares fit (torque rows weighted above force rows, so attitude is kept first).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.optimize import lsq_linear

from vehicles.hexarotor_sponge.params import HexarotorParams

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class RotorGeometry:
    """Positions, thrust axes and drag signs of the six rotors in the body frame."""

    position_m_body: FloatArray
    """(6, 3) rotor centres in [m]."""
    axis_body: FloatArray
    """(6, 3) unit thrust directions."""
    spin: FloatArray
    """(6,) +1 / -1: sign of the rotor's drag torque about its axis."""


def rotor_geometry(params: HexarotorParams) -> RotorGeometry:
    """The rotors of ``params`` laid out as described in the module docstring."""
    pos, axes, spin = [], [], []
    for i in range(6):
        ang = math.pi / 3.0 * i + math.pi / 6.0
        radial = np.array([math.cos(ang), math.sin(ang), 0.0])
        tilt = params.rotor_tilt_rad * (1.0 if i % 2 == 0 else -1.0)
        tangential = np.array([-math.sin(ang), math.cos(ang), 0.0])
        pos.append(params.rotor_radius_m * radial)
        axes.append(math.cos(tilt) * np.array([0.0, 0.0, 1.0]) + math.sin(tilt) * tangential)
        spin.append(1.0 if i % 2 == 0 else -1.0)
    return RotorGeometry(np.array(pos), np.array(axes), np.array(spin))


def wrench_matrix(params: HexarotorParams) -> FloatArray:
    """(6, 6) map from rotor thrusts in [N] to body wrench [force N; torque N m] about the CoM."""
    geo = rotor_geometry(params)
    force = geo.axis_body.T
    torque = (
        np.cross(geo.position_m_body, geo.axis_body)
        + params.drag_torque_m * geo.spin[:, None] * geo.axis_body
    ).T
    return np.asarray(np.vstack([force, torque]))


@dataclass(frozen=True)
class Allocation:
    """Rotor thrusts for one wanted wrench."""

    thrust_n: FloatArray
    """(6,) thrusts in [N], within ``[0, thrust_max_n]``."""
    saturated: bool
    """True when the wanted wrench needed a thrust beyond the limits (the result is the bounded
    least-squares fit, not the exact wrench)."""


class Allocator:
    """Allocates body wrenches of one vehicle (the matrix and its inverse computed once)."""

    def __init__(self, params: HexarotorParams) -> None:
        self.matrix = wrench_matrix(params)
        self.inverse = np.linalg.inv(self.matrix)
        self.thrust_max_n = params.thrust_max_n
        self._weights = np.array([1.0, 1.0, 1.0, 100.0, 100.0, 100.0])

    def allocate(self, wrench_body: FloatArray) -> Allocation:
        """Thrusts in [N] for a body wrench (6,) [N; N m] about the centre of mass."""
        exact = self.inverse @ np.asarray(wrench_body, dtype=np.float64)
        if np.all(exact >= 0.0) and np.all(exact <= self.thrust_max_n):
            return Allocation(np.asarray(exact, dtype=np.float64), False)
        w = self._weights
        fit = lsq_linear(w[:, None] * self.matrix, w * wrench_body, bounds=(0.0, self.thrust_max_n))
        return Allocation(np.asarray(fit.x, dtype=np.float64), True)

    def wrench(self, thrust_n: FloatArray) -> FloatArray:
        """Body wrench (6,) [N; N m] produced by thrusts (6,) in [N]."""
        return np.asarray(self.matrix @ np.asarray(thrust_n, dtype=np.float64))
