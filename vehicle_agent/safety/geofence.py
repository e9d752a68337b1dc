"""A vehicle's geofence watched along its flight, every control tick (pure).

The fence itself follows from the show file (:mod:`showfile.geofence`).
"""

from __future__ import annotations

from collections.abc import Sequence

from showfile.geofence import Geofence

BOUNDARY_TOLERANCE_M = 2.0**-17
"""How far in [m] (7.6 µm) a measured position may lie outside the fence and still count as on its
boundary: the resolution of the positions an autopilot reports. MAVLink's LOCAL_POSITION_NED and
SET_POSITION_TARGET_LOCAL_NED carry x, y, z as 32-bit floats (common.xml), spaced 2^-17 m apart
from 64 to 128 m off the autopilot's origin (finer nearer it); a setpoint on the boundary, sent,
flown and read back, is rounded by up to half that each way. Less is the boundary measured, not a
vehicle beyond it (counted as a breach, it landed the vehicle in ``fault`` "by 0.00 m")."""


class FenceWatch:
    """One vehicle's fence along its flight, checked every control tick. A point nearer the last
    point found inside than that point's clearance (its distance to the nearest edge) is inside
    too, the fence being convex: the edges are read again only as the vehicle nears them or
    leaves the disc (a vehicle writing over its board, every few hundred ticks)."""

    def __init__(self, fence: Geofence) -> None:
        self.fence = fence
        self._x_m, self._y_m, self._clearance_sq_m2 = 0.0, 0.0, -1.0

    def distance_outside_m(self, p_m_enu: Sequence[float]) -> float:
        """As :meth:`Geofence.distance_outside_m` (the same value, 0 inside)."""
        fence = self.fence
        x, y, z = float(p_m_enu[0]), float(p_m_enu[1]), float(p_m_enu[2])
        dx, dy = x - self._x_m, y - self._y_m
        if dx * dx + dy * dy < self._clearance_sq_m2 and fence.floor_z_m <= z <= fence.ceiling_z_m:
            return 0.0  # NaN fails both tests: it is judged below
        outside_m = fence.distance_outside_m((x, y, z))
        if outside_m == 0.0:
            clearance_m = -fence.edge_offset_m(x, y)
            self._x_m, self._y_m, self._clearance_sq_m2 = x, y, clearance_m * clearance_m
        return outside_m
