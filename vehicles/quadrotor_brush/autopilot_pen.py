"""The brush of a quadrotor flown behind an autopilot, modelled from its pose (pure).

The Airshow brush is passive: a shaft on a linear bearing hanging along the body's -z axis. Its tip,
press, stroke width and board contact follow from the vehicle's position and attitude alone
(:func:`vehicles.quadrotor_brush.brush.brush_state`, the same model as the simulated world), so
the agent can measure ink and the writing point's error of a vehicle it only hears over MAVLink
(``VehicleKind.autopilot_world``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from vehicles.kind import AutopilotWorld, PenReading
from vehicles.quadrotor_brush.brush import brush_state
from vehicles.quadrotor_brush.params import BrushParams, WorldParams
from vehicles.surface import Vec3

if TYPE_CHECKING:
    from vehicles.kind import Mat3


@dataclass(frozen=True)
class BrushPen:
    """The brush over a horizontal board that spans the world (see
    :class:`vehicles.kind.AutopilotPen`)."""

    params: BrushParams
    """Length, travel and width model of the brush."""
    board_height_m: float
    """Height of the horizontal board surface in [m] (world z)."""

    def read(self, position_m_enu: Vec3, rotation_body_to_enu: Mat3) -> PenReading:
        """The brush of a vehicle at ``position_m_enu`` in [m] turned by ``rotation_body_to_enu``
        (its third column: the body z axis in ENU, along which the shaft hangs)."""
        r = rotation_body_to_enu
        body_z_enu = np.array([[r[0][2], r[1][2], r[2][2]]])
        state = brush_state(
            self.params, np.array([position_m_enu]), body_z_enu, self.board_height_m
        )
        tip = state.tip_m_enu[0]
        tip_m_enu = (float(tip[0]), float(tip[1]), float(tip[2]))
        return PenReading(tip_m_enu, float(state.width_m[0]), bool(state.contact[0]))


def autopilot_world(world: WorldParams) -> AutopilotWorld:
    """The brush over the board and the motion capture of the simulated ``world``."""
    return AutopilotWorld(
        pen=BrushPen(world.brush, world.board_height_m),
        mocap_latency_s=world.mocap.latency_s,
        mocap_noise_std_m=world.mocap.noise_std_m,
    )
