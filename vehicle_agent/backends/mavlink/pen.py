"""The pen a MAVLink vehicle carries, read from the attitude it reports (pure).

Nothing senses the pen: its kind's room models it from the vehicle's pose
(:class:`vehicles.kind.AutopilotPen`, from ``VehicleKind.autopilot_world``), in ENU with the body
forward-left-up. Here, at the MAVLink boundary, the ATTITUDE (NED, body forward-right-down) becomes
that rotation, and contact counts only over the vehicle's board.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from vehicle_agent.backends.mavlink.frames import Vec3, attitude_ned_to_enu, euler_to_matrix
from vehicles.kind import AutopilotPen, PenReading


@dataclass(frozen=True)
class PenOverBoard:
    """A kind's pen model and the board under it."""

    pen: AutopilotPen
    """The pen, modelled from the pose by the vehicle's kind (contact on the whole plane)."""
    over_board: Callable[[Vec3], bool] | None = None
    """Whether a point lies over the board (None: the board spans the world)."""

    def read(self, position_m_enu: Vec3, attitude_ned_rad: Vec3) -> PenReading:
        """The pen of a vehicle at ``position_m_enu`` in [m] with this ATTITUDE (roll, pitch,
        yaw in [rad], NED, FRD)."""
        rotation_body_to_enu = euler_to_matrix(*attitude_ned_to_enu(*attitude_ned_rad))
        reading = self.pen.read(position_m_enu, rotation_body_to_enu)
        if not reading.contact or self.over_board is None or self.over_board(reading.tip_m_enu):
            return reading
        return PenReading(reading.tip_m_enu, 0.0, False)  # on the plane, beyond the board
