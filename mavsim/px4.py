"""The PX4 flavour of the simulated autopilot: OFFBOARD instead of GUIDED, where it differs.

- OFFBOARD (internal GUIDED) is entered, and the vehicle armed in it, only while a setpoint stream
  is alive ("proof of life": a setpoint within COM_OF_LOSS_T); setpoints are taken as proof of
  life in any mode;
- in OFFBOARD and armed the vehicle follows setpoints from the ground: there is no NAV_TAKEOFF;
- when the stream stops for COM_OF_LOSS_T it leaves OFFBOARD for Hold (AUTO.LOITER) and says so
  ("Failsafe: ..."), which a companion sees as a mode change;
- setpoints ArduCopter would stop on are ignored (:func:`mavsim.wire.px4_view`), a yaw not given
  is held (PX4 has no WP_YAW_BEHAVIOR), attitude thrust is normalised thrust;
- after AUTO.LAND touches down it disarms and, in the same breath, reports the mode the pilot
  last chose again (OFFBOARD, if the companion flew it): a companion must not read that as a
  takeover;
- its geofence is GF_MAX_HOR_DIST / GF_MAX_VER_DIST / GF_ACTION (:mod:`mavsim.fence`);
- it sends STATUSTEXT only to links where it hears a ground station's heartbeat (the endpoint).
"""

from __future__ import annotations

import math

from mavsim.autopilot import SEVERITY_WARNING, Autopilot, Result
from mavsim.config import VehicleConfig
from mavsim.control import Target
from mavsim.modes import CopterMode
from mavsim.params import Flavor
from mavsim.wire import AttitudeSetpoint, GuidedSetpoint


class Px4Autopilot(Autopilot):
    """An :class:`Autopilot` with PX4's OFFBOARD rules."""

    flavor: Flavor = "px4"
    timeout_param = "COM_OF_LOSS_T"
    shapes_targets = False
    takeoff_owns_ground = False

    def __init__(self, config: VehicleConfig) -> None:
        super().__init__(config)
        self.signal_s = -math.inf
        """Vehicle time of the last setpoint (proof of life), in [s]."""
        self.chosen_mode = self.mode
        """The mode last selected by a command (PX4's "user intention"), restored after LAND."""

    @property
    def signal_alive(self) -> bool:
        return self.now_s - self.signal_s <= self.guided_timeout_s

    @property
    def wp_yaw_behavior(self) -> float:
        return 0.0

    @property
    def thrust_is_thrust(self) -> bool:
        return True

    def set_mode(self, custom_mode: int) -> Result:
        if custom_mode == CopterMode.GUIDED and not self.signal_alive:
            self.say(SEVERITY_WARNING, "Offboard mode rejected: no setpoint stream")
            return Result.FAILED
        before = self.mode
        result = super().set_mode(custom_mode)
        if result == Result.ACCEPTED and custom_mode == CopterMode.LAND:
            self.chosen_mode = before if before != CopterMode.LAND else self.chosen_mode
        elif result == Result.ACCEPTED:
            self.chosen_mode = self.mode
        return result

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

    def guided_setpoint(self, sp: GuidedSetpoint, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        return super().guided_setpoint(sp, stamp_ms)

    def position_target(self, target: Target, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        return super().position_target(target, stamp_ms)

    def attitude_setpoint(self, sp: AttitudeSetpoint, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        return super().attitude_setpoint(sp, stamp_ms)

    def _guided_failsafe(self) -> None:
        if self.armed and not self.signal_alive:
            silent_s = self.now_s - self.signal_s
            self.mode = CopterMode.LOITER
            self._enter_mode()
            self.say(SEVERITY_WARNING, f"Failsafe: offboard lost for {silent_s:.1f}s, holding")

    def _landed(self) -> None:
        """Disarm, and show the mode chosen before LAND again in the same heartbeat."""
        super()._landed()
        self.mode = self.chosen_mode
