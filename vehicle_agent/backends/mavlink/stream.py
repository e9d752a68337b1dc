"""The setpoint stream to one autopilot: what a setpoint becomes on the wire, at its rate.

Position setpoints are SET_POSITION_TARGET_LOCAL_NED with position, velocity, acceleration and
the held heading (type_mask ``0x0800``: only the yaw rate ignored), so the autopilot never turns
the vehicle on its own.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

from vehicle_agent.backends.base import Setpoint
from vehicle_agent.backends.mavlink.frames import LocalFrame
from vehicle_agent.backends.mavlink.link import MavlinkLink
from vehicle_agent.backends.mavlink.setpoints import (
    MAV_FRAME_LOCAL_NED,
    TYPE_MASK_POSITION_VELOCITY_ACCEL_YAW,
    ned_target,
)
from vehicle_agent.backends.mavlink.settings import MavlinkSettings
from vehicle_agent.backends.mavlink.state import LinkState


class SetpointStream:
    """Encodes and sends setpoints; counts them; remembers when the last one went out."""

    def __init__(
        self,
        settings: MavlinkSettings,
        frame: LocalFrame,
        state: LinkState,
        link: Callable[[], MavlinkLink],
    ) -> None:
        self.settings = settings
        self.frame = frame
        self.state = state
        self._link = link
        self.sent = 0
        """Setpoints sent so far."""
        self.last_sent_s = -math.inf
        """Agent time in [s] of the last setpoint sent."""
        self.heading_ned_rad = 0.0
        """The heading held in every setpoint, in [rad] from north (the take-off heading)."""

    def new_flight(self, heading_ned_rad: float) -> None:
        """A take-off: hold this heading."""
        self.heading_ned_rad = heading_ned_rad

    @property
    def period_s(self) -> float:
        """Time in [s] between setpoints (half a control period early, so none is skipped)."""
        return 1.0 / self.settings.setpoint_rate_hz - 0.5 * self.settings.control_period_s

    def due(self, now_s: float) -> bool:
        return now_s - self.last_sent_s >= self.period_s

    def send(self, setpoint: Setpoint, now_s: float) -> None:
        """One control period of the stream: the setpoint, when one is due."""
        if self.due(now_s):
            self.send_position(setpoint, now_s)

    def send_position(self, setpoint: Setpoint, now_s: float) -> None:
        """SET_POSITION_TARGET_LOCAL_NED: p, v, a and the held heading (yaw rate ignored)."""
        st, mav = self.state, self._link().mav
        t = ned_target(setpoint, self.frame)
        message = mav.set_position_target_local_ned_encode(
            _stamp_ms(now_s), st.system_id or 0, st.component_id or 0,
            MAV_FRAME_LOCAL_NED, TYPE_MASK_POSITION_VELOCITY_ACCEL_YAW, *t.position_m_ned,
            *t.velocity_mps_ned, *t.acceleration_mps2_ned, self.heading_ned_rad, 0.0,
        )  # fmt: skip
        self._send(message, now_s)

    def send_proof_of_life(self, hold: Setpoint, now_s: float) -> None:
        """What PX4 needs on the ground before OFFBOARD and arming: the hold point."""
        self.send_position(hold, now_s)

    def _send(self, message: Any, now_s: float) -> None:
        if self._link().send(message):
            self.last_sent_s = now_s
            self.sent += 1


def _stamp_ms(now_s: float) -> int:
    return int(now_s * 1000) & 0xFFFFFFFF
