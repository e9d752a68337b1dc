"""The brush a MAVLink vehicle carries, modelled from its pose (pure).

The Airshow brush is passive: a shaft on a linear bearing hanging along the body's -z axis. Its tip,
press, stroke width and board contact follow from the vehicle's position and attitude alone
(``vehicles.quadrotor_brush.brush``, the same model as the in-process simulator), so the agent can
measure ink and the writing point's error for a vehicle it only hears over MAVLink. Contact counts
only over the vehicle's board.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from vehicle_agent.backends.mavlink_frames import Vec3, attitude_ned_to_enu, euler_to_matrix
from vehicles.quadrotor_brush.brush import brush_state
from vehicles.quadrotor_brush.params import BrushParams


@dataclass(frozen=True)
class BrushReading:
    """The brush at one instant."""

    tip_m_enu: Vec3
    """Brush tip in [m], ENU."""
    width_m: float
    """Stroke width in [m] it paints now (0 without contact)."""
    contact: bool
    """Whether the tip touches the board."""


@dataclass(frozen=True)
class BrushModel:
    """Brush geometry and the board under it."""

    params: BrushParams
    """Length, travel and width model of the brush."""
    board_height_m: float
    """Height of the horizontal board surface in [m] (world z)."""
    over_board: Callable[[Vec3], bool] | None = None
    """Whether a point lies over the board (None: the board spans the world)."""

    def read(self, position_m_enu: Vec3, attitude_ned_rad: Vec3) -> BrushReading:
        """The brush of a vehicle at ``position_m_enu`` with this ATTITUDE (NED, FRD)."""
        rotation = euler_to_matrix(*attitude_ned_to_enu(*attitude_ned_rad))
        body_z = np.array([[rotation[0][2], rotation[1][2], rotation[2][2]]])
        state = brush_state(self.params, np.array([position_m_enu]), body_z, self.board_height_m)
        tip = (float(state.tip_m_enu[0, 0]), float(state.tip_m_enu[0, 1]),
               float(state.tip_m_enu[0, 2]))  # fmt: skip
        contact = bool(state.contact[0]) and (self.over_board is None or self.over_board(tip))
        return BrushReading(tip, float(state.width_m[0]) if contact else 0.0, contact)
