"""The autopilot's own geofence, as ArduCopter and PX4 define it by parameters (pure).

ArduCopter: FENCE_ENABLE; FENCE_TYPE bit 1 a circle of FENCE_RADIUS [m] around home, bit 0 a
maximum altitude FENCE_ALT_MAX [m] above home; on a breach FENCE_ACTION: 0 report only, 2 LAND,
4 BRAKE, any other RTL. PX4: GF_MAX_HOR_DIST and GF_MAX_VER_DIST [m] from home (0: off); on a
breach GF_ACTION: 0 nothing, 1 a warning, 2 Hold, 3 Return, 4 flight termination, 5 Land.
"""

from __future__ import annotations

import math
from typing import Literal

from mavsim.modes import CopterMode
from mavsim.params import ParamTable

Vec3 = tuple[float, float, float]
Action = CopterMode | Literal["report", "terminate"]


def fence_breach(params: ParamTable, position_m_enu: Vec3, home_m_enu: Vec3) -> str | None:
    """Which limit the vehicle is beyond (``circle``/``altitude``), or None."""
    horizontal = math.hypot(position_m_enu[0] - home_m_enu[0], position_m_enu[1] - home_m_enu[1])
    height = position_m_enu[2] - home_m_enu[2]
    if params.flavor == "px4":
        max_hor, max_ver = params["GF_MAX_HOR_DIST"], params["GF_MAX_VER_DIST"]
        if max_hor > 0.0 and horizontal > max_hor:
            return "circle"
        if max_ver > 0.0 and height > max_ver:
            return "altitude"
        return None
    if not params["FENCE_ENABLE"]:
        return None
    kind = int(params["FENCE_TYPE"])
    if kind & 2 and horizontal > params["FENCE_RADIUS"]:
        return "circle"
    if kind & 1 and height > params["FENCE_ALT_MAX"]:
        return "altitude"
    return None


def fence_action(params: ParamTable) -> Action | None:
    """What the autopilot does on a breach (None: nothing at all)."""
    if params.flavor == "px4":
        px4 = {0: None, 1: "report", 2: CopterMode.LOITER, 3: CopterMode.RTL, 4: "terminate"}
        return px4.get(int(params["GF_ACTION"]), CopterMode.LAND)  # type: ignore[return-value]
    ardupilot = {0: "report", 2: CopterMode.LAND, 4: CopterMode.BRAKE}
    return ardupilot.get(int(params["FENCE_ACTION"]), CopterMode.RTL)  # type: ignore[return-value]
