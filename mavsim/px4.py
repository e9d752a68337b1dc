"""The PX4 flavour of the simulated autopilot: OFFBOARD instead of GUIDED, where it differs.

- OFFBOARD (internal GUIDED) is entered, and the vehicle armed in it, only while a setpoint stream
  is alive ("proof of life": a setpoint within ``guided_timeout_s``, PX4's COM_OF_LOSS_T);
  setpoints are taken as proof of life in any mode;
- in OFFBOARD and armed the vehicle follows setpoints from the ground: there is no NAV_TAKEOFF;
- when the stream stops for ``guided_timeout_s`` it leaves OFFBOARD for Hold (AUTO.LOITER) and
  says so ("Failsafe: ..."), which a companion sees as a mode change.
"""

from __future__ import annotations

import math

from mavsim.airframe import AttitudeThrust
from mavsim.autopilot import SEVERITY_WARNING, Autopilot, Result
from mavsim.config import VehicleConfig
from mavsim.control import Target
from mavsim.modes import CopterMode


class Px4Autopilot(Autopilot):
    """An :class:`Autopilot` with PX4's OFFBOARD rules."""

    def __init__(self, config: VehicleConfig) -> None:
        super().__init__(config)
        self.signal_s = -math.inf
        """Vehicle time of the last setpoint (proof of life), in [s]."""

    @property
    def signal_alive(self) -> bool:
        return self.now_s - self.signal_s <= self.config.guided_timeout_s

    def set_mode(self, custom_mode: int) -> Result:
        if custom_mode == CopterMode.GUIDED and not self.signal_alive:
            self.say(SEVERITY_WARNING, "Offboard mode rejected: no setpoint stream")
            return Result.FAILED
        return super().set_mode(custom_mode)

    def _arming_refusal(self) -> str | None:
        reason = super()._arming_refusal()
        if reason is None and self.mode == CopterMode.GUIDED and not self.signal_alive:
            return "Arming denied: offboard signal lost"
        return reason

    def takeoff(self, altitude_m: float) -> Result:
        """AUTO.TAKEOFF is not simulated: a PX4 companion climbs with OFFBOARD setpoints."""
        return Result.UNSUPPORTED

    def accepts_setpoints(self) -> bool:
        return self.mode == CopterMode.GUIDED and self.armed

    def position_target(self, target: Target, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        return super().position_target(target, stamp_ms)

    def attitude_target_in(self, command: AttitudeThrust, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        return super().attitude_target_in(command, stamp_ms)

    def _guided_failsafe(self) -> None:
        if self.armed and not self.signal_alive:
            silent_s = self.now_s - self.signal_s
            self.mode = CopterMode.LOITER
            self._enter_mode()
            self.say(SEVERITY_WARNING, f"Failsafe: offboard lost for {silent_s:.1f}s, holding")
