"""Where a vehicle writes: a plane in the world with the glyph's own 2-D axes on it.

One frame for every kind: a horizontal board seen from above (Airshow brush quadrotor), a vertical
wall seen from the vehicle in front of it (Flying Calligrapher hexarotor), a floor area seen from
above (ground writer). Glyph coordinates ``(x, y)`` are metres on the surface with ``y`` up for the
reader; ``normal`` points from the surface towards the vehicle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Literal

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
Orientation = Literal["horizontal", "vertical", "floor"]
Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class Surface:
    """A writing plane: origin at the centre of the writing area, reader's x and y axes on it."""

    origin_m_enu: Vec3
    """Centre of the writing area on the surface, in [m], world ENU."""
    x_axis_enu: Vec3
    """Unit vector of the glyph's x axis (the reader's right), world ENU."""
    y_axis_enu: Vec3
    """Unit vector of the glyph's y axis (the reader's up), world ENU."""
    orientation: Orientation
    """``horizontal`` board, ``vertical`` wall or ``floor``."""

    @classmethod
    def of(cls, orientation: Orientation, origin_m_enu: Vec3, yaw_rad: float) -> Surface:
        """The surface of a show board.

        ``horizontal``/``floor``: the glyph's x axis is world east turned by ``yaw_rad`` about
        z, its y axis 90 deg further, the normal is world up. ``vertical``: the glyph's x axis is
        horizontal along the wall (east turned by ``yaw_rad``), its y axis is world up, and the
        normal ``x cross y`` points out of the wall towards the vehicle (south for yaw 0).
        """
        c, s = math.cos(yaw_rad), math.sin(yaw_rad)
        if orientation == "vertical":
            return cls(origin_m_enu, (c, s, 0.0), (0.0, 0.0, 1.0), orientation)
        return cls(origin_m_enu, (c, s, 0.0), (-s, c, 0.0), orientation)

    @property
    def normal_enu(self) -> FloatArray:
        """Unit normal ``x cross y``, from the surface towards the vehicle, world ENU (a new
        array each call: callers may change it)."""
        return self._basis[:, 2].copy()

    @cached_property
    def _basis(self) -> FloatArray:
        """Columns: x axis, y axis, normal (3, 3), read-only. Built once: a live vehicle maps
        its brush tip every control tick, and ``np.cross`` on 3-vectors costs ~60 us."""
        (ax, ay, az), (bx, by, bz) = self.x_axis_enu, self.y_axis_enu
        normal = (ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx)
        basis = np.column_stack([self.x_axis_enu, self.y_axis_enu, normal]).astype(np.float64)
        basis.setflags(write=False)
        return basis

    def to_world(self, xy_m: FloatArray, standoff_m: float | FloatArray = 0.0) -> FloatArray:
        """Surface points (n, 2) in [m], ``standoff_m`` along the normal -> world (n, 3) ENU."""
        xy = np.asarray(xy_m, dtype=np.float64)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f"expected (n, 2) surface points, got shape {xy.shape}")
        local = np.column_stack([xy, np.broadcast_to(standoff_m, (xy.shape[0],))])
        return np.asarray(local @ self._basis.T + np.asarray(self.origin_m_enu))

    def to_surface(self, p_m_enu: FloatArray) -> FloatArray:
        """World points (n, 3) ENU -> surface coordinates (n, 2) in [m] (standoff dropped)."""
        return self.to_local(p_m_enu)[:, :2]

    def standoff_m(self, p_m_enu: FloatArray) -> FloatArray:
        """Signed distance (n,) in [m] of world points from the surface along its normal."""
        return self.to_local(p_m_enu)[:, 2]

    def to_local(self, p_m_enu: FloatArray) -> FloatArray:
        """World points (n, 3) ENU -> (x, y, standoff) (n, 3) in [m]."""
        p = np.asarray(p_m_enu, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ValueError(f"expected (n, 3) world points, got shape {p.shape}")
        return np.asarray((p - np.asarray(self.origin_m_enu)) @ self._basis)
