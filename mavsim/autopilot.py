"""An ArduCopter-like autopilot for one simulated vehicle (pure: time injected, no I/O).

What it reproduces, where it matters for a companion computer (measured on ArduCopter SITL):

- arming is refused (MAV_RESULT_FAILED + "PreArm: ..." text) until the estimator has a position
  source, ``position_source_delay_s`` after start; while disarmed any mode may be selected (as
  ArduCopter does), armed GUIDED/LOITER/RTL need the position too;
- GUIDED (custom mode 4) is entered with MAV_CMD_DO_SET_MODE; MAV_CMD_NAV_TAKEOFF climbs to param 7
  metres above home; SET_POSITION_TARGET_LOCAL_NED and SET_ATTITUDE_TARGET are honoured only in
  GUIDED and armed; with no setpoint for ``guided_timeout_s`` (GUID_TIMEOUT) the vehicle stops where
  it is (this one also says so in a STATUSTEXT);
- LAND descends at ``land_speed_mps`` and disarms on touchdown; LOITER/BRAKE/STABILIZE/ALT_HOLD
  hold position (no pilot sticks in a simulator); RTL returns home, then lands;
- armed on the ground without taking off for ``disarm_delay_s`` -> auto-disarm.

Positions inside are the show frame (ENU); the endpoint converts MAVLink's LOCAL_NED, whose
origin is ``home_m_enu``, at its boundary.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass, replace
from enum import IntEnum
from typing import Literal

from mavsim.airframe import Airframe, AttitudeThrust
from mavsim.config import VehicleConfig
from mavsim.control import PositionController, Target
from mavsim.modes import HOLDING_MODES, NEEDS_POSITION, NOT_ARMABLE, CopterMode, mode_name

Vec3 = tuple[float, float, float]
Submode = Literal["ground", "takeoff", "track", "attitude", "stopped"]

SEVERITY_CRITICAL = 2
SEVERITY_WARNING = 4
SEVERITY_INFO = 6
LANDED_DWELL_S = 1.0
"""Time on the ground in LAND before the autopilot disarms."""


class Result(IntEnum):
    """MAV_RESULT values."""

    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4


@dataclass(frozen=True)
class AttitudeTarget:
    """A SET_ATTITUDE_TARGET as the inner loop takes it."""

    command: AttitudeThrust
    """Attitude (ENU) and thrust per unit mass."""
    received_s: float
    """Vehicle time of receipt in [s]."""


class Autopilot:
    """Modes, arming, takeoff, guided setpoints, land and failsafes of one vehicle."""

    def __init__(self, config: VehicleConfig) -> None:
        self.config = config
        self.airframe = Airframe(config)
        self.controller = PositionController(
            config.gains,
            gravity_mps2=self.airframe.gravity_mps2,
            tilt_max_rad=config.tilt_max_rad,
            thrust_max_mps2=self.airframe.max_thrust_mps2,
        )
        self.mode = CopterMode.STABILIZE
        self.armed = False
        self.submode: Submode = "ground"
        self.target = Target(position_m_enu=config.home_m_enu)
        self.attitude_target: AttitudeTarget | None = None
        self.takeoff_alt_m: float | None = None
        self.last_setpoint_s = -math.inf
        self.setpoint_stamp_ms = 0
        """``time_boot_ms`` of the setpoint being tracked, echoed in POSITION_TARGET_LOCAL_NED."""
        self.setpoints_received = 0
        self.mocap_received = 0
        self.now_s = 0.0
        self.flight_time_s = 0.0
        self._armed_idle_since_s = 0.0
        self._on_ground_since_s: float | None = None
        self.texts: list[tuple[int, str]] = []
        """STATUSTEXTs (severity, text) waiting to be sent; the endpoint drains this list."""

    # --- state as telemetry sees it ------------------------------------------------------------
    @property
    def position_source_ready(self) -> bool:
        """The estimator has a position source (arming and GUIDED allowed)."""
        return self.now_s >= self.config.position_source_delay_s

    @property
    def on_ground(self) -> bool:
        return self.airframe.on_ground

    @property
    def battery_fraction(self) -> float:
        """Remaining battery 0..1 (linear in flight time)."""
        return max(0.0, 1.0 - self.flight_time_s / self.config.battery_endurance_s)

    @property
    def landed_state(self) -> int:
        """MAV_LANDED_STATE: 1 on ground, 2 in air, 3 taking off, 4 landing."""
        if self.on_ground:
            return 1
        if self.submode == "takeoff":
            return 3
        return 4 if self.mode == CopterMode.LAND else 2

    def say(self, severity: int, text: str) -> None:
        """Queue a STATUSTEXT."""
        self.texts.append((severity, text[:50]))

    # --- commands --------------------------------------------------------------------------------
    def arm(self) -> Result:
        """MAV_CMD_COMPONENT_ARM_DISARM param1 = 1."""
        if self.armed:
            return Result.ACCEPTED
        reason = self._arming_refusal()
        if reason is not None:
            self.say(SEVERITY_CRITICAL, reason)
            return Result.FAILED
        self.armed = True
        self._armed_idle_since_s = self.now_s
        self.submode = "ground"
        self.controller.reset()
        self.say(SEVERITY_INFO, "Arming motors")
        return Result.ACCEPTED

    def _arming_refusal(self) -> str | None:
        if self.config.arm_refusal is not None:
            return f"PreArm: {self.config.arm_refusal}"
        if not self.position_source_ready:
            return "PreArm: Need Position Estimate"
        if self.mode in NOT_ARMABLE:
            return "Arm: Mode not armable"
        return None

    def disarm(self, *, force: bool = False) -> Result:
        """MAV_CMD_COMPONENT_ARM_DISARM param1 = 0 (param2 21196 forces it in the air)."""
        if not self.armed:
            return Result.ACCEPTED
        if not self.on_ground and not force:
            self.say(SEVERITY_CRITICAL, "Disarm: vehicle is flying")
            return Result.FAILED
        self._disarm()
        return Result.ACCEPTED

    def _disarm(self) -> None:
        self.armed = False
        self.submode = "ground"
        self.attitude_target = None
        self.say(SEVERITY_INFO, "Disarming motors")

    def set_mode(self, custom_mode: int) -> Result:
        """MAV_CMD_DO_SET_MODE / SET_MODE with a custom mode; a pilot's switch goes here too.
        Disarmed, any mode may be selected (ArduCopter skips the checks then)."""
        try:
            mode = CopterMode(custom_mode)
        except ValueError:
            self.say(SEVERITY_WARNING, f"Unknown mode {custom_mode}")
            return Result.FAILED
        if mode in NEEDS_POSITION and self.armed and not self.position_source_ready:
            self.say(SEVERITY_WARNING, f"Mode change to {mode.name} failed: requires position")
            return Result.FAILED
        if mode != self.mode:
            self.mode = mode
            self._enter_mode()
        return Result.ACCEPTED

    def _enter_mode(self) -> None:
        """Hold where the vehicle is; LAND and RTL start from here too."""
        here = self.airframe.position_m_enu
        self.target = Target(position_m_enu=here, yaw_rad=self.target.yaw_rad)
        self.attitude_target = None
        self.controller.reset()
        if self.submode != "ground" or not self.on_ground:
            self.submode = "track"
        self.takeoff_alt_m = None

    def takeoff(self, altitude_m: float) -> Result:
        """MAV_CMD_NAV_TAKEOFF: climb to ``altitude_m`` above home (GUIDED, armed, landed)."""
        if self.mode != CopterMode.GUIDED or not self.armed or not self.on_ground:
            self.say(SEVERITY_WARNING, "Takeoff: need GUIDED, armed and landed")
            return Result.FAILED
        if not altitude_m > 0.0:
            return Result.DENIED
        here = self.airframe.position_m_enu
        self.takeoff_alt_m = self.config.home_m_enu[2] + altitude_m
        self.target = Target(position_m_enu=here, yaw_rad=self.target.yaw_rad)
        self.submode = "takeoff"
        self.controller.reset()
        return Result.ACCEPTED

    def land(self) -> Result:
        """MAV_CMD_NAV_LAND: switch to LAND."""
        return self.set_mode(CopterMode.LAND)

    def terminate(self) -> Result:
        """MAV_CMD_DO_FLIGHTTERMINATION: motors off at once."""
        if self.armed:
            self._disarm()
        return Result.ACCEPTED

    # --- guided setpoints ------------------------------------------------------------------------
    def accepts_setpoints(self) -> bool:
        """GUIDED, armed and flying (or taking off): setpoints are honoured."""
        return self.mode == CopterMode.GUIDED and self.armed and self.submode != "ground"

    def position_target(self, target: Target, stamp_ms: int) -> bool:
        """A SET_POSITION_TARGET_LOCAL_NED (already in ENU); False when ignored."""
        if not self.accepts_setpoints():
            return False
        if self.submode == "stopped":
            self.say(SEVERITY_INFO, "Guided: setpoints resumed")
        self.target = target
        self.submode = "track"
        self.takeoff_alt_m = None
        self.last_setpoint_s = self.now_s
        self.setpoint_stamp_ms = stamp_ms
        self.setpoints_received += 1
        return True

    def attitude_target_in(self, command: AttitudeThrust, stamp_ms: int) -> bool:
        """A SET_ATTITUDE_TARGET (already ENU, thrust per unit mass); False when ignored."""
        if not self.accepts_setpoints():
            return False
        self.attitude_target = AttitudeTarget(command, self.now_s)
        self.submode = "attitude"
        self.takeoff_alt_m = None
        self.last_setpoint_s = self.now_s
        self.setpoint_stamp_ms = stamp_ms
        self.setpoints_received += 1
        return True

    # --- the loop --------------------------------------------------------------------------------
    def step(self, now_s: float) -> None:
        """One autopilot period ending at vehicle time ``now_s``: decide, then step the physics."""
        dt = self.airframe.dt_s
        self.now_s = now_s
        command = self._command(dt)
        self.airframe.step(command)
        if self.armed:
            self.flight_time_s += dt
        self._after_step()

    def _command(self, dt: float) -> AttitudeThrust:
        yaw = self.target.yaw_rad
        if not self.armed or (self.submode == "ground" and self.on_ground):
            return AttitudeThrust(0.0, 0.0, yaw, 0.0)
        if self.mode == CopterMode.GUIDED:
            self._guided_failsafe()
            if self.submode == "takeoff":
                self._advance_takeoff(dt)
            elif self.submode == "attitude" and self.attitude_target is not None:
                return self.attitude_target.command
        elif self.mode == CopterMode.LAND:
            self._advance_descent(dt)
        elif self.mode == CopterMode.RTL:
            self._advance_return(dt)
        elif self.mode not in HOLDING_MODES:
            return AttitudeThrust(0.0, 0.0, yaw, 0.0)
        if self.mode == CopterMode.GUIDED and self.submode == "track":
            self._propagate_target(dt)
        p, v = self.airframe.position_m_enu, self.airframe.velocity_mps_enu
        return self.controller.update(self.target, p, v, dt)

    def _guided_failsafe(self) -> None:
        """GUID_TIMEOUT: no setpoint for too long -> stop where the vehicle is."""
        if self.submode not in ("track", "attitude") or self.last_setpoint_s == -math.inf:
            return
        silent_s = self.now_s - self.last_setpoint_s
        if silent_s <= self.config.guided_timeout_s:
            return
        self.submode = "stopped"
        self.attitude_target = None
        self.target = Target(
            position_m_enu=self.airframe.position_m_enu, yaw_rad=self.target.yaw_rad
        )
        self.say(SEVERITY_WARNING, f"Guided failsafe: no setpoint for {silent_s:.1f}s, stopping")

    def _advance_takeoff(self, dt: float) -> None:
        alt = (
            self.takeoff_alt_m if self.takeoff_alt_m is not None else self.target.position_m_enu[2]
        )
        x, y, z = self.target.position_m_enu
        speed = self.config.takeoff_speed_mps
        z_next = min(z + speed * dt, alt)
        vz = speed if z_next < alt else 0.0
        self.target = replace(
            self.target, position_m_enu=(x, y, z_next), velocity_mps_enu=(0, 0, vz)
        )
        if abs(self.airframe.position_m_enu[2] - alt) < 0.05 and z_next >= alt:
            self.submode = "track"
            self.takeoff_alt_m = None
            self.target = replace(self.target, velocity_mps_enu=(0.0, 0.0, 0.0))

    def _advance_descent(self, dt: float) -> None:
        x, y, z = self.target.position_m_enu
        speed = self.config.land_speed_mps
        z_next = max(z - speed * dt, self.airframe.ground_z_m - 0.3)
        self.target = replace(
            self.target, position_m_enu=(x, y, z_next), velocity_mps_enu=(0.0, 0.0, -speed),
            acceleration_mps2_enu=(0.0, 0.0, 0.0),
        )  # fmt: skip

    def _advance_return(self, dt: float) -> None:
        home = self.config.home_m_enu
        x, y, z = self.target.position_m_enu
        dx, dy = home[0] - x, home[1] - y
        distance = math.hypot(dx, dy)
        step = self.config.land_speed_mps * dt
        if distance <= step:
            self.target = Target(position_m_enu=(home[0], home[1], z), yaw_rad=self.target.yaw_rad)
            if math.dist(self.airframe.position_m_enu[:2], home[:2]) < 0.1:
                self.mode = CopterMode.LAND
            return
        self.target = replace(
            self.target, position_m_enu=(x + dx * step / distance, y + dy * step / distance, z),
            velocity_mps_enu=(0.0, 0.0, 0.0), acceleration_mps2_enu=(0.0, 0.0, 0.0),
        )  # fmt: skip

    def _propagate_target(self, dt: float) -> None:
        """Between setpoints the target moves on with its velocity and acceleration (ArduPilot's
        position controller does the same), so 50 Hz setpoints drive a 100+ Hz loop smoothly."""
        t = self.target
        p, v, a = t.position_m_enu, t.velocity_mps_enu, t.acceleration_mps2_enu
        if v == (0.0, 0.0, 0.0) and a == (0.0, 0.0, 0.0):
            return
        self.target = replace(
            t,
            position_m_enu=_vec(p[i] + v[i] * dt + 0.5 * a[i] * dt * dt for i in range(3)),
            velocity_mps_enu=_vec(v[i] + a[i] * dt for i in range(3)),
        )

    def hold_position_m_enu(self) -> Vec3:
        """Where a setpoint without a position keeps the vehicle: the current target in flight."""
        if self.submode == "track":
            return self.target.position_m_enu
        return self.airframe.position_m_enu

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
            self._disarm()
            return
        if self.submode in ("takeoff", "attitude"):
            self._armed_idle_since_s = now
        elif now - self._armed_idle_since_s >= self.config.disarm_delay_s:
            self.say(SEVERITY_INFO, "Auto disarm: no takeoff")
            self._disarm()


def _vec(values: Iterable[float]) -> Vec3:
    x, y, z = values
    return (float(x), float(y), float(z))


def describe(autopilot: Autopilot) -> str:
    """One line for logs: mode, armed, submode, position."""
    p = autopilot.airframe.position_m_enu
    armed = "ARMED" if autopilot.armed else "disarmed"
    where = ", ".join(f"{v:.2f}" for v in p)
    return f"{mode_name(autopilot.mode)} {armed} {autopilot.submode} at ({where})"
