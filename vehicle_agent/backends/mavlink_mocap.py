"""Indoor flight: forward motion-capture poses to the autopilot as its position source.

With ``mocap: vision_position_estimate`` (ArduPilot with EK3_SRC1_POSXY = 6 ExternalNav, PX4 with
EKF2_EV_CTRL) or ``att_pos_mocap`` the backend sends the pose from ``mocap_source`` at
``mocap_rate_hz``, converted to the vehicle's LOCAL_NED frame. The source is whatever the venue's
mocap client provides; it is asked for the pose at the agent time of the tick.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from vehicle_agent.backends.mavlink_frames import (
    LocalFrame,
    Vec3,
    attitude_enu_to_ned,
    euler_to_quaternion,
)

if TYPE_CHECKING:
    from vehicle_agent.backends.mavlink_link import MavlinkLink
    from vehicle_agent.backends.mavlink_settings import MavlinkSettings


@dataclass(frozen=True)
class MocapPose:
    """One motion-capture frame of the vehicle, in the show frame."""

    position_m_enu: Vec3
    """Vehicle reference point in [m], ENU."""
    attitude_rad: Vec3 = (0.0, 0.0, 0.0)
    """Roll, pitch, yaw of the FLU body in ENU, in [rad]."""
    time_s: float | None = None
    """Capture time in [s] of the agent clock (None: now)."""


MocapSource = Callable[[float], MocapPose | None]
"""Agent time in [s] -> the latest pose, or None when the mocap has no frame."""


class MocapForwarder:
    """Sends poses at a fixed rate when the settings ask for it."""

    def __init__(self, settings: MavlinkSettings, frame: LocalFrame, source: MocapSource | None):
        self.kind = settings.mocap
        self.period_s = 1.0 / settings.mocap_rate_hz
        self.frame = frame
        self.source = source
        self.sent = 0
        self._last_s = float("-inf")

    def forward(self, link: MavlinkLink, state: Any, now_s: float) -> None:
        """Send a pose if one is due and available."""
        if (
            self.kind == "none"
            or self.source is None
            or now_s - self._last_s + 1e-9 < self.period_s
        ):
            return
        pose = self.source(now_s)
        if pose is None:
            return
        self._last_s = now_s
        x, y, z = self.frame.position_to_ned(pose.position_m_enu)
        roll, pitch, yaw = attitude_enu_to_ned(*pose.attitude_rad)
        usec = int((pose.time_s if pose.time_s is not None else now_s) * 1e6)
        if self.kind == "vision_position_estimate":
            message = link.mav.vision_position_estimate_encode(usec, x, y, z, roll, pitch, yaw)
        else:
            q = euler_to_quaternion(roll, pitch, yaw)
            message = link.mav.att_pos_mocap_encode(usec, q, x, y, z)
        if link.send(message):
            self.sent += 1
