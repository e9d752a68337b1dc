"""An ArduCopter-like autopilot for one simulated vehicle (pure: time injected, no I/O).

What it reproduces, where it matters for a companion computer (measured on ArduCopter SITL):

- arming is refused (MAV_RESULT_FAILED + "PreArm: ..." text) until the estimator has a position
  source, ``position_source_delay_s`` after start; while disarmed any mode may be selected (as
  ArduCopter does), armed GUIDED/LOITER/RTL need the position too;
- a failing pre-arm check (that one, stale mocap, or ``prearm_fault``, set from outside) shows in
  SYS_STATUS and is said when it begins or changes, every 30 s while it lasts (PX4: on change
  only) and on MAV_CMD_RUN_PREARM_CHECKS;
- GUIDED (custom mode 4) is entered with MAV_CMD_DO_SET_MODE; MAV_CMD_NAV_TAKEOFF ramps the
  throttle over TKOFF_SLEW_TIME until the vehicle lifts, then climbs to param 7 metres above home;
  a setpoint before it has lifted ends the take-off on the ground (ArduCopter's ``land_complete``);
  SET_POSITION_TARGET_LOCAL_NED and SET_ATTITUDE_TARGET are honoured only in
  GUIDED and armed, read as ArduCopter reads them (:mod:`mavsim.wire`; an invalid one stops the
  vehicle where it is) and flown as :mod:`mavsim.guided` says (GUID_TIMEOUT, yaw, thrust), along
  ArduCopter's jerk-limited path towards the target (:mod:`mavsim.shaping`) with its PSC gains:
  a 1 m step is half done in 1.2 s with about 5 % overshoot, a written path trails by 0.09 s;
- parameters (:mod:`mavsim.params`) are set and read over MAVLink and change the behaviour;
- its fence (FENCE_ENABLE, circle and maximum altitude around home) switches to FENCE_ACTION's mode
  on a breach;
- LAND descends at ``land_speed_mps`` and disarms on touchdown; LOITER/BRAKE/STABILIZE/ALT_HOLD
  hold position (no pilot sticks in a simulator); RTL returns home, then lands;
- armed on the ground without taking off for ``disarm_delay_s`` -> auto-disarm.

Positions inside are the show frame (ENU); the endpoint converts MAVLink's LOCAL_NED, whose
origin is ``home_m_enu``, at its boundary.
"""

from __future__ import annotations

import math
from dataclasses import replace

from mavsim.airframe import AttitudeThrust
from mavsim.auto_modes import descend, go_home
from mavsim.autopilot_core import SEVERITY_CRITICAL, SEVERITY_INFO, AutopilotCore
from mavsim.config import PositionGains
from mavsim.control import Target
from mavsim.fence import fence_action, fence_breach
from mavsim.guided import (
    AttitudeHold,
    Heading,
    attitude_command,
    climb_rate_mps,
    propagate,
    timed_out,
)
from mavsim.modes import HOLDING_MODES, CopterMode, mode_name
from mavsim.shaping import ShapeLimits, shape_limits
from mavsim.wire import AttitudeSetpoint

LANDED_DWELL_S = 1.0
"""Time on the ground in LAND before the autopilot disarms."""


class Autopilot(AutopilotCore):
    """Modes, arming, takeoff, guided setpoints, land and failsafes of one vehicle, flown."""

    # --- the loop --------------------------------------------------------------------------------
    def step(self, now_s: float) -> None:
        """One autopilot period ending at vehicle time ``now_s``: decide, then step the physics."""
        dt = self.airframe.dt_s
        self.now_s = now_s
        self._follow_gain_params()
        command = self._command(dt)
        self.airframe.step(command)
        self.battery.step(self.airframe.rotor_thrust_n, dt)
        self._after_step()
        self._check_fence()
        self._announce_prearm()

    def _follow_gain_params(self) -> None:
        """Each flies its position gains as they are set now (unless the configuration fixes
        them): ArduCopter PSC_POSXY_P, PSC_VELXY_P, PSC_VELXY_I; PX4 MPC_XY_P, MPC_XY_VEL_P_ACC,
        MPC_XY_VEL_I_ACC, MPC_Z_P, MPC_Z_VEL_P_ACC."""
        if self.config.gains is not None:
            return
        p = self.params
        if self.flavor == "px4":
            gains = PositionGains.px4(
                p["MPC_XY_P"],
                p["MPC_XY_VEL_P_ACC"],
                p["MPC_XY_VEL_I_ACC"],
                p["MPC_Z_P"],
                p["MPC_Z_VEL_P_ACC"],
            )
        else:
            gains = PositionGains.ardupilot(p["PSC_POSXY_P"], p["PSC_VELXY_P"], p["PSC_VELXY_I"])
        if gains != self.controller.gains:
            self.controller.gains = gains

    def _command(self, dt: float) -> AttitudeThrust:
        yaw = self.target.yaw_rad
        if not self.armed or (self.submode == "ground" and self.on_ground):
            return AttitudeThrust(0.0, 0.0, yaw, 0.0)
        if self.mode == CopterMode.GUIDED:
            self._guided_failsafe()
            if self.submode == "takeoff" and self.on_ground:
                return self._spool_up()
            if self.submode == "takeoff":
                self._advance_takeoff()
            elif self.submode == "attitude" and self.attitude_hold is not None:
                return self._attitude_command(dt)
        elif self.mode == CopterMode.LAND:
            self._advance_descent(dt)
        elif self.mode == CopterMode.RTL:
            self._advance_return(dt)
        elif self.mode not in HOLDING_MODES:
            return AttitudeThrust(0.0, 0.0, yaw, 0.0)
        p, v = self.airframe.position_m_enu, self.airframe.velocity_mps_enu
        flown = self.target
        if self.mode == CopterMode.GUIDED and self.submode == "track":
            self.target = propagate(self.target, self.heading, p, dt)
            flown = self.target
            if self.shapes_targets:
                flown = self.shaper.step(self.target, p, v, self.shape_limits, dt)
        elif self.mode == CopterMode.GUIDED and self.submode == "takeoff":
            limits = self.shape_limits
            speed = min(limits.speed_up_mps, self.config.takeoff_speed_mps)
            flown = self.shaper.step(self.target, p, v, replace(limits, speed_up_mps=speed), dt)
        return self.controller.update(flown, p, v, dt)

    def _spool_up(self) -> AttitudeThrust:
        """NAV_TAKEOFF on the ground: the throttle rises over TKOFF_SLEW_TIME until the vehicle
        lifts; the climb starts from where it leaves the ground."""
        slew_s = max(self.params["TKOFF_SLEW_TIME"], 0.1)
        fraction = min((self.now_s - self._takeoff_since_s) / slew_s, 1.0)
        here = self.airframe.position_m_enu
        self.target = Target(position_m_enu=here, yaw_rad=self.target.yaw_rad)
        return AttitudeThrust(
            0.0, 0.0, self.target.yaw_rad, fraction * self.airframe.max_thrust_mps2
        )

    @property
    def shape_limits(self) -> ShapeLimits:
        """The shaped path's limits (WPNAV_*, PSC_JERK_*)."""
        return shape_limits(self.params)

    def _attitude_command(self, dt: float) -> AttitudeThrust:
        hold = self.attitude_hold
        assert hold is not None
        climb = 0.0
        if not hold.use_thrust:
            up, down = self.params["WPNAV_SPEED_UP"], self.params["WPNAV_SPEED_DN"]
            climb = climb_rate_mps(hold.setpoint.thrust, up, down)
            hold = replace(hold, climb_z_m=hold.climb_z_m + climb * dt)
            self.attitude_hold = hold
        g = self.config.position_gains
        return attitude_command(
            hold, z_m=self.airframe.position_m_enu[2], vz_mps=self.airframe.velocity_mps_enu[2],
            thrust_max_mps2=self.airframe.max_thrust_mps2, gravity_mps2=self.airframe.gravity_mps2,
            kp_z=g.kp_z, kd_z=g.kd_z, climb_mps=climb,
        )  # fmt: skip

    def _guided_failsafe(self) -> None:
        """GUID_TIMEOUT: velocity and acceleration targets zeroed (the vehicle stops), attitude
        targets levelled at the heading with the height held; position targets hold anyway."""
        if self.submode not in ("track", "attitude") or self.last_setpoint_s == -math.inf:
            return
        if self.now_s - self.last_setpoint_s <= self.guided_timeout_s:
            return
        if self.submode == "attitude" and self.attitude_hold is not None:
            hold = self.attitude_hold
            level = AttitudeSetpoint(0.0, 0.0, self.airframe.attitude_rad[2], 0.5)
            z = hold.climb_z_m if not hold.use_thrust else self.airframe.position_m_enu[2]
            self.attitude_hold = AttitudeHold(level, False, z)
        elif self.submode == "track":
            self.target = timed_out(self.control, self.target)
            if self.heading.mode == "rate":
                self.heading = Heading()

    def _check_fence(self) -> None:
        """The autopilot's own fence (:mod:`mavsim.fence`): on a breach in flight, its action,
        once per breach."""
        breach = fence_breach(self.params, self.airframe.position_m_enu, self.home_m_enu)
        if breach is None or not self.armed or self.on_ground:
            self.fence_breached = breach is not None and self.fence_breached
            return
        if self.fence_breached:
            return
        self.fence_breached = True
        action = fence_action(self.params)
        if action is None:
            return
        self.say(SEVERITY_CRITICAL, f"Fence Breached: {breach}")
        if action == "terminate":
            self.terminate()
        elif action != "report" and action != self.mode:
            self.mode = action
            self._enter_mode()

    def _advance_takeoff(self) -> None:
        """NAV_TAKEOFF in the air: one shaped climb to the altitude (no faster than
        ``takeoff_speed_mps``), then the guided hold from where the path is."""
        alt = self.takeoff_alt_m
        alt = alt if alt is not None else self.target.position_m_enu[2]
        x, y, _ = self.target.position_m_enu
        self.target = Target((x, y, alt), yaw_rad=self.target.yaw_rad)
        z, vz = self.airframe.position_m_enu[2], self.airframe.velocity_mps_enu[2]
        if abs(z - alt) < 0.05 and abs(vz) < 0.1:
            self.submode = "track"
            self.takeoff_alt_m = None
            self.controller.reset()  # the lift-off's transient is not a hover error

    def _advance_descent(self, dt: float) -> None:
        speed = self.config.land_speed_mps
        self.target = descend(self.target, speed, self.airframe.ground_z_m, dt)

    def _advance_return(self, dt: float) -> None:
        home = self.home_m_enu
        self.target = go_home(self.target, home, self.config.land_speed_mps, dt)
        if math.dist(self.airframe.position_m_enu[:2], home[:2]) < 0.1:
            self.mode = CopterMode.LAND

    def _landed(self) -> None:
        """LAND touched down and dwelt: disarm."""
        self._disarm()

    def _after_step(self) -> None:
        """Landing detection, auto-disarm, leaving the ground."""
        now = self.now_s
        if not self.armed:
            return
        if not self.on_ground:
            self._on_ground_since_s = None
            self._armed_idle_since_s = now
            if self.submode == "ground":
                self.submode = "track"
            return
        if self._on_ground_since_s is None:
            self._on_ground_since_s = now
        if self.mode == CopterMode.LAND and now - self._on_ground_since_s >= LANDED_DWELL_S:
            self._landed()
            return
        if self.submode in ("takeoff", "attitude"):
            self._armed_idle_since_s = now
        elif now - self._armed_idle_since_s >= self.config.disarm_delay_s:
            self.say(SEVERITY_INFO, "Auto disarm: no takeoff")
            self._disarm()


def describe(autopilot: Autopilot) -> str:
    """One line for logs: mode, armed, submode, position."""
    p = autopilot.airframe.position_m_enu
    armed = "ARMED" if autopilot.armed else "disarmed"
    where = ", ".join(f"{v:.2f}" for v in p)
    return f"{mode_name(autopilot.mode)} {armed} {autopilot.submode} at ({where})"
