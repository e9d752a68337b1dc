"""Horizontal writing board (Airshow): board-local 2-D coordinates <-> world ENU."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from planner.errors import PlannerError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BoardFrame:
    """A horizontal writing board; board x/y are world east/north rotated by ``yaw_rad`` about z."""

    center_m_enu: tuple[float, float, float]
    """Centre of the writing area ON the board surface, world ENU in [m]."""
    yaw_rad: float = 0.0
    """Rotation of the board x axis from world east, counter-clockwise about world z, in [rad]."""

    @property
    def surface_z_m(self) -> float:
        """Height of the board surface in world ENU in [m]."""
        return float(self.center_m_enu[2])

    def _rotation(self) -> FloatArray:
        c, s = math.cos(self.yaw_rad), math.sin(self.yaw_rad)
        return np.array([[c, -s], [s, c]])

    def to_world(self, xy_board_m: FloatArray) -> FloatArray:
        """Board-local points (n, 2) in [m] -> points (n, 3) on the board surface, world ENU."""
        xy = np.asarray(xy_board_m, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise PlannerError(f"expected (n, 2) board points, got shape {xy.shape}")
        world = np.empty((xy.shape[0], 3))
        world[:, :2] = xy @ self._rotation().T + np.asarray(self.center_m_enu[:2])
        world[:, 2] = self.surface_z_m
        return world

    def to_board(self, p_m_enu: FloatArray) -> FloatArray:
        """World points (n, 3) in [m] -> board-local (n, 2) (height above the board dropped)."""
        p = np.asarray(p_m_enu, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise PlannerError(f"expected (n, 3) world points, got shape {p.shape}")
        return np.asarray((p[:, :2] - np.asarray(self.center_m_enu[:2])) @ self._rotation())

    def height_above_m(self, p_m_enu: FloatArray) -> FloatArray:
        """Height of world points (n, 3) above the board surface in [m], shape (n,)."""
        return np.asarray(np.asarray(p_m_enu, dtype=np.float64)[:, 2] - self.surface_z_m)
