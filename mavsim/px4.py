"""The PX4 flavour of the simulated autopilot: OFFBOARD instead of GUIDED, where it differs.

- OFFBOARD (internal GUIDED) is entered, and the vehicle armed in it, only while a setpoint stream
  is alive ("proof of life": a setpoint within COM_OF_LOSS_T); setpoints are taken as proof of
  life in any mode;
- in OFFBOARD and armed the vehicle follows setpoints from the ground: there is no NAV_TAKEOFF;
- when the stream stops for COM_OF_LOSS_T, the failsafe COM_OBL_RC_ACT flies instead (PX4 v1.16's
  failsafe state machine): 0 (the default) Position mode, also without RC (PX4 PR 26289 stops
  that only after v1.16), 1 Altitude, 2 Stabilized, 3 Return, 4 Land, 5 Hold, 6 Terminate,
  7 Disarm, announced as PX4's failsafe event words it ("Failsafe activated: switching to
  Position"); the heartbeat shows that mode, the user's choice stays OFFBOARD, so a stream that
  comes back returns the vehicle to OFFBOARD, and a failsafe landing ends with OFFBOARD shown;
- Position and Altitude mode without sticks get no valid setpoint; the position controller's own
  failsafe then holds zero velocity ("stop and wait"), not a position: the vehicle stops and
  drifts as its velocity estimate does. On PX4 SIH v1.16 (GPS-grade estimate) that drift was
  0.57 m, 1.1 m (to the ground) and 0.05 m down in three runs, 0.2-0.3 m sideways; mavsim's
  estimate is perfect, so it stops and stays;
- a setpoint without a position (velocity only) is flown with no position loop at all;
- setpoints ArduCopter would stop on are ignored (:func:`mavsim.wire.px4_view`), a yaw not given
  is held (PX4 has no WP_YAW_BEHAVIOR), attitude thrust is normalised thrust;
- after AUTO.LAND touches down it disarms and, in the same breath, reports the mode the pilot
  last chose again (OFFBOARD, if the companion flew it): a companion must not read that as a
  takeover;
- its geofence is GF_MAX_HOR_DIST / GF_MAX_VER_DIST / GF_ACTION (:mod:`mavsim.fence`), around
  a home that MAV_CMD_DO_SET_HOME moves; beyond its distance it refuses to arm;
- it sends STATUSTEXT only to links where it hears a ground station's heartbeat (the endpoint);
- its pack is full whenever it is disarmed (SITL's battery simulator) and it has no
  MAV_CMD_BATTERY_RESET (:mod:`mavsim.battery`).
"""

from __future__ import annotations

import math
from dataclasses import replace

from mavsim.airframe import AttitudeThrust
from mavsim.autopilot import Autopilot
from mavsim.autopilot_core import SEVERITY_CRITICAL, SEVERITY_WARNING, Result
from mavsim.config import VehicleConfig
from mavsim.control import Target
from mavsim.fence import fence_breach
from mavsim.modes import NOT_ARMABLE, CopterMode
from mavsim.params import Flavor
from mavsim.wire import AttitudeSetpoint, GuidedSetpoint

OBL_TERMINATE, OBL_DISARM = 6, 7
OFFBOARD_LOSS_MODES = {
    0: CopterMode.BRAKE,  # Position mode (shown as POSCTL)
    1: CopterMode.ALT_HOLD,
    2: CopterMode.STABILIZE,
    3: CopterMode.RTL,
    4: CopterMode.LAND,
    5: CopterMode.LOITER,  # Hold
}
"""COM_OBL_RC_ACT -> the mode flown while the offboard signal is lost."""
OFFBOARD_LOSS_NAMES = {0: "Position", 1: "Altitude", 2: "Stabilized", 3: "Return", 4: "Land",
                       5: "Hold", 6: "Terminate", 7: "Disarm"}  # fmt: skip
"""How PX4's failsafe announcement names each action (its event text, "switching to {action}")."""


class Px4Autopilot(Autopilot):
    """An :class:`Autopilot` with PX4's OFFBOARD rules."""

    flavor: Flavor = "px4"
    timeout_param = "COM_OF_LOSS_T"
    shapes_targets = False
    takeoff_owns_ground = False
    prearm_repeat_s = math.inf

    def __init__(self, config: VehicleConfig) -> None:
        super().__init__(config)
        self.signal_s = -math.inf
        """Vehicle time of the last setpoint (proof of life), in [s]."""
        self.chosen_mode = self.mode
        """The mode last selected by a command (PX4's "user intention")."""
        self.after_disarm_mode = self.mode
        """The last chosen mode that allows arming: the user intention again once disarmed (so
        after AUTO.LAND, OFFBOARD if the companion flew it)."""
        self.failsafe_mode: CopterMode | None = None
        """The offboard-loss failsafe's mode while it flies instead of OFFBOARD."""
        self.velocity_only = False
        """The last setpoint had no position: no position loop (PX4 takes NaN as "not held")."""

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
        result = super().set_mode(custom_mode)
        if result == Result.ACCEPTED:
            self.failsafe_mode = None
            self.chosen_mode = CopterMode(custom_mode)
            if self.chosen_mode not in NOT_ARMABLE:
                self.after_disarm_mode = self.chosen_mode
        return result

    def prearm_failure(self) -> str | None:
        """Besides the estimator's checks, PX4's geofence (``geofenceCheck.cpp``, in its words):
        with an action (GF_ACTION) it fails while the vehicle is beyond GF_MAX_HOR_DIST of its
        home, on the ground too."""
        failure = super().prearm_failure()
        beyond = fence_breach(self.params, self.airframe.position_m_enu, self.home_m_enu)
        if failure is None and beyond == "circle" and int(self.params["GF_ACTION"]) != 0:
            return "Geofence: exceeding maximum distance to Home"
        return failure

    @property
    def prearm_bit(self) -> bool:
        """PX4 sets the bit for the mode it is in (SYS_STATUS.hpp, ``can_arm_mode_flags`` of
        the current nav_state): clear in OFFBOARD with no stream, whatever the checks say."""
        return super().prearm_bit and self._arming_refusal() is None

    def _arming_refusal(self) -> str | None:
        reason = super()._arming_refusal()
        if reason is None and self.mode == CopterMode.GUIDED and not self.signal_alive:
            return "Arming denied: offboard signal lost"
        return reason

    def takeoff(self, altitude_m: float) -> Result:
        """AUTO.TAKEOFF is not simulated: a PX4 companion climbs with OFFBOARD setpoints."""
        return Result.UNSUPPORTED

    def battery_reset(self, mask: int, percentage: float) -> Result:
        """PX4 has no MAV_CMD_BATTERY_RESET: Commander's default answer, UNSUPPORTED."""
        return Result.UNSUPPORTED

    def step(self, now_s: float) -> None:
        """One period; disarmed, the pack is full again, as PX4 SITL's battery simulator has
        it (``BatterySimulator::Run``: ``_battery_percentage = 1`` whenever not armed)."""
        super().step(now_s)
        if not self.armed:
            self.battery.refill()

    def accepts_setpoints(self) -> bool:
        return self.mode == CopterMode.GUIDED and self.armed

    def guided_setpoint(self, sp: GuidedSetpoint, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        taken = super().guided_setpoint(sp, stamp_ms)
        if taken:
            self.velocity_only = sp.position_m_enu is None
        return taken

    def position_target(self, target: Target, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        return super().position_target(target, stamp_ms)

    def attitude_setpoint(self, sp: AttitudeSetpoint, stamp_ms: int) -> bool:
        self.signal_s = self.now_s
        return super().attitude_setpoint(sp, stamp_ms)

    def _guided_failsafe(self) -> None:
        """Checked every loop in any mode instead (:meth:`_command`)."""

    def _command(self, dt: float) -> AttitudeThrust:
        if self.armed:
            self._watch_offboard_signal()
        if self.armed and self._no_position_loop():
            here = self.airframe.position_m_enu
            self.target = replace(self.target, position_m_enu=here)
            self.controller.reset()
        return super()._command(dt)

    def _no_position_loop(self) -> bool:
        """Velocity-only OFFBOARD, or Position/Altitude mode without sticks (stop and wait)."""
        if self.mode == CopterMode.GUIDED:
            return self.velocity_only and self.submode == "track"
        if self.mode in (CopterMode.BRAKE, CopterMode.ALT_HOLD):
            self.target = replace(self.target, velocity_mps_enu=(0.0, 0.0, 0.0))
            return True
        return False

    def _watch_offboard_signal(self) -> None:
        """COM_OBL_RC_ACT while OFFBOARD is chosen and the stream is lost; OFFBOARD again when
        it is back."""
        if self.chosen_mode != CopterMode.GUIDED:
            return
        if self.failsafe_mode is None and not self.signal_alive:
            action = int(self.params["COM_OBL_RC_ACT"])
            name = OFFBOARD_LOSS_NAMES.get(action, "Position")
            self.say(SEVERITY_CRITICAL, f"Failsafe activated: switching to {name}")
            if action == OBL_TERMINATE:
                self.terminate()
            elif action == OBL_DISARM:
                self.disarm(force=True)
            else:
                self._fly_failsafe(OFFBOARD_LOSS_MODES.get(action, CopterMode.BRAKE))
        elif self.failsafe_mode is not None and self.signal_alive:
            self.failsafe_mode = None
            self.mode = CopterMode.GUIDED
            self._enter_mode()

    def _fly_failsafe(self, mode: CopterMode) -> None:
        self.failsafe_mode = mode
        self.mode = mode
        self._enter_mode()
        self.velocity_only = False

    def _disarm(self) -> None:
        """Disarm; in the same heartbeat the mode shown is the user's last armable choice (after
        a LAND, commanded or failsafe: OFFBOARD if that was it)."""
        super()._disarm()
        self.failsafe_mode = None
        self.chosen_mode = self.mode = self.after_disarm_mode
