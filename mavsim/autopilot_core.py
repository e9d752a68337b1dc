"""The state of a simulated autopilot and what commands and setpoints do to it (pure; no loop).

The loop that flies the vehicle from this state is :class:`mavsim.autopilot.Autopilot`; the
behaviours both reproduce are listed there.
"""

from __future__ import annotations

import math
from dataclasses import replace
from enum import IntEnum
from typing import Literal

from mavsim.airframe import Airframe
from mavsim.battery import SimBattery
from mavsim.config import VehicleConfig
from mavsim.control import PositionController, Target
from mavsim.guided import (
    GUID_OPTIONS_THRUST_AS_THRUST,
    AttitudeHold,
    Heading,
    heading_of,
    merge,
)
from mavsim.mocap import MOCAP_TIMEOUT_S, STALE_REFUSAL, fuses_mocap
from mavsim.modes import NEEDS_POSITION, NOT_ARMABLE, CopterMode
from mavsim.params import Flavor, ParamTable
from mavsim.shaping import TargetShaper
from mavsim.wire import AttitudeSetpoint, Control, GuidedSetpoint

Vec3 = tuple[float, float, float]
Submode = Literal["ground", "takeoff", "track", "attitude"]

SEVERITY_CRITICAL = 2
SEVERITY_WARNING = 4
SEVERITY_INFO = 6
PREARM_PREFIX: dict[Flavor, str] = {"ardupilot": "PreArm: ", "px4": "Preflight Fail: "}
"""How each autopilot begins the text of a failing pre-arm check."""


class Result(IntEnum):
    """MAV_RESULT values."""

    ACCEPTED = 0
    TEMPORARILY_REJECTED = 1
    DENIED = 2
    UNSUPPORTED = 3
    FAILED = 4


class AutopilotCore:
    """State, commands and guided setpoints of one vehicle; :class:`mavsim.autopilot.Autopilot`
    adds the loop that flies them."""

    flavor: Flavor = "ardupilot"
    timeout_param = "GUID_TIMEOUT"
    """The parameter that holds the setpoint timeout in [s]."""
    shapes_targets = True
    """Guided targets are flown along ArduCopter's jerk-limited path (:mod:`mavsim.shaping`)."""
    takeoff_owns_ground = True
    """A setpoint before NAV_TAKEOFF has lifted the vehicle ends the take-off on the ground
    (ArduCopter: guided position control does nothing while ``land_complete``)."""
    prearm_repeat_s = 30.0
    """A failing pre-arm check is said again this often in [s] while it lasts (ArduPilot's
    PREARM_DISPLAY_PERIOD; PX4 says it only when its checks change)."""

    def __init__(self, config: VehicleConfig) -> None:
        self.config = config
        boot = dict(config.params)
        if config.guided_timeout_s is not None:
            boot.setdefault(self.timeout_param, config.guided_timeout_s)
        self.params = ParamTable(self.flavor, boot, frozen=config.frozen_params)
        self.airframe = Airframe(config)
        self.controller = PositionController(
            config.position_gains,
            gravity_mps2=self.airframe.gravity_mps2,
            tilt_max_rad=config.tilt_max_rad,
            thrust_max_mps2=self.airframe.max_thrust_mps2,
        )
        self.mode = CopterMode.STABILIZE
        self.armed = False
        self.submode: Submode = "ground"
        self.target = Target(position_m_enu=config.home_m_enu)
        (hx, hy, hz), (ox, oy, oz) = config.home_m_enu, config.boot_home_offset_m
        self.home_m_enu: Vec3 = (hx + ox, hy + oy, hz + oz)
        """The autopilot's home in [m], show frame ENU: its fence's centre, where RTL returns."""
        self.shaper = TargetShaper()
        """ArduCopter's jerk-limited path towards the guided target (:mod:`mavsim.shaping`)."""
        self.control: Control = "pos"
        """Which guided controller flies ``target`` (see mavsim.wire)."""
        self.heading = Heading()
        self.attitude_hold: AttitudeHold | None = None
        self.takeoff_alt_m: float | None = None
        self.fence_breached = False
        self.last_setpoint_s = -math.inf
        self.setpoint_stamp_ms = 0
        """``time_boot_ms`` of the setpoint being tracked, echoed in POSITION_TARGET_LOCAL_NED."""
        self.setpoints_received = 0
        self.mocap_received = 0
        self.mocap_at_s = -math.inf
        """Vehicle time in [s] of the last mocap pose."""
        self._viso_type_at_boot = self.params["VISO_TYPE"] if self.flavor == "ardupilot" else 0.0
        self.ekf_origin_lla: tuple[float, float, float] | None = None
        """EKF origin (lat [deg], lon [deg], alt [m]) a companion set (SET_GPS_GLOBAL_ORIGIN)."""
        self.now_s = 0.0
        self.battery = SimBattery(rotor_radius_m=self.airframe.params.rotor_radius_m)
        """Its pack, drawn by the airframe's thrust each period (:mod:`mavsim.battery`)."""
        self._armed_idle_since_s = 0.0
        self._on_ground_since_s: float | None = None
        self._takeoff_since_s = 0.0
        self.texts: list[tuple[int, str]] = []
        """STATUSTEXTs (severity, text) waiting to be sent; the endpoint drains this list."""
        self.prearm_fault: str | None = config.arm_refusal
        """A pre-arm check failing now, in the words after the autopilot's prefix (None: none):
        ``config.arm_refusal`` from boot; a test or a rehearsal sets and clears it while the
        vehicle runs, as a real estimator settles (PX4 SITL said "horizontal velocity unstable"
        for 30-60 s before most take-offs)."""
        self._prearm_said: str | None = None
        self._prearm_said_s = -math.inf

    # --- state as telemetry sees it ------------------------------------------------------------
    @property
    def guided_timeout_s(self) -> float:
        """The setpoint timeout in [s] (GUID_TIMEOUT; PX4 COM_OF_LOSS_T)."""
        return self.params[self.timeout_param]

    @property
    def position_source_ready(self) -> bool:
        """The estimator has a position source (arming and GUIDED allowed): after the start
        delay, and, while mocap is the source, with a recent pose (:mod:`mavsim.mocap`)."""
        return self.now_s >= self.config.position_source_delay_s and not self.mocap_stale

    @property
    def fuses_mocap(self) -> bool:
        """Mocap is the estimator's position source (the parameters say so)."""
        return fuses_mocap(self.flavor, self.params, self._viso_type_at_boot)

    @property
    def mocap_stale(self) -> bool:
        """Mocap is the position source and no pose came recently."""
        return self.fuses_mocap and self.now_s - self.mocap_at_s > MOCAP_TIMEOUT_S[self.flavor]

    def mocap_pose(self) -> None:
        """A VISION_POSITION_ESTIMATE or ATT_POS_MOCAP arrived."""
        self.mocap_received += 1
        self.mocap_at_s = self.now_s

    @property
    def on_ground(self) -> bool:
        return self.airframe.on_ground

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
        self._restart_control()
        self.say(SEVERITY_INFO, "Arming motors")
        return Result.ACCEPTED

    def prearm_failure(self) -> str | None:
        """The pre-arm check failing now, in the autopilot's words (None: they pass): what
        SYS_STATUS's MAV_SYS_STATUS_PREARM_CHECK reports. Arming checks the mode besides."""
        if self.prearm_fault is not None:
            return PREARM_PREFIX[self.flavor] + self.prearm_fault
        if self.now_s >= self.config.position_source_delay_s and self.mocap_stale:
            return STALE_REFUSAL[self.flavor]
        if not self.position_source_ready:
            return "PreArm: Need Position Estimate"
        return None

    @property
    def prearm_bit(self) -> bool:
        """SYS_STATUS's MAV_SYS_STATUS_PREARM_CHECK health bit: set while the checks pass."""
        return self.prearm_failure() is None

    def _arming_refusal(self) -> str | None:
        reason = self.prearm_failure()
        if reason is None and self.mode in NOT_ARMABLE:
            return "Arm: Mode not armable"
        return reason

    def _announce_prearm(self) -> None:
        """While disarmed, say a failing pre-arm check when it begins or changes and again every
        ``prearm_repeat_s`` (ArduPilot's AP_Arming::update; PX4 reports its health checks on
        change): a ground station learns why before it tries to arm."""
        failure = None if self.armed else self.prearm_failure()
        due = self.now_s - self._prearm_said_s >= self.prearm_repeat_s
        if failure is not None and (failure != self._prearm_said or due):
            self.say(SEVERITY_CRITICAL, failure)
            self._prearm_said_s = self.now_s
        self._prearm_said = failure

    def run_prearm_checks(self) -> Result:
        """MAV_CMD_RUN_PREARM_CHECKS (a ground station's "check"): say the failing pre-arm
        check now; refused while armed, as ArduPilot does."""
        if self.armed:
            return Result.TEMPORARILY_REJECTED
        self._prearm_said_s = -math.inf
        self._announce_prearm()
        return Result.ACCEPTED

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
        self.attitude_hold = None
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
        self.control, self.heading, self.attitude_hold = "pos", Heading(), None
        self._restart_control()
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
        self._takeoff_since_s = self.now_s
        self._restart_control()
        return Result.ACCEPTED

    def _restart_control(self) -> None:
        """Forget the loop's integral and the shaped path: fly on from the vehicle's state."""
        self.controller.reset()
        self.shaper.reset()

    def land(self) -> Result:
        """MAV_CMD_NAV_LAND: switch to LAND."""
        return self.set_mode(CopterMode.LAND)

    def set_home_here(self) -> Result:
        """MAV_CMD_DO_SET_HOME param1 = 1: home where the vehicle is (both autopilots; PX4's
        Commander: ``setHomePosition(true)``, TEMPORARILY_REJECTED without a position)."""
        if not self.position_source_ready:
            return Result.TEMPORARILY_REJECTED
        p = self.airframe.position_m_enu
        self.home_m_enu = (float(p[0]), float(p[1]), float(p[2]))
        return Result.ACCEPTED

    def terminate(self) -> Result:
        """MAV_CMD_DO_FLIGHTTERMINATION: motors off at once."""
        if self.armed:
            self._disarm()
        return Result.ACCEPTED

    def battery_reset(self, mask: int, percentage: float) -> Result:
        """MAV_CMD_BATTERY_RESET as ArduPilot answers it (``handle_command_battery_reset``):
        each battery in ``mask`` that exists (one here: bit 0) counts ``percentage`` [%] left;
        bits of batteries it lacks are ignored, and it is accepted armed or not. Disarmed on
        the ground, mavsim takes it as the crew's fresh pack (:mod:`mavsim.battery`)."""
        if mask & 1:
            fresh_pack = not self.armed and self.on_ground
            self.battery.reset_remaining(percentage, fresh_pack=fresh_pack)
        return Result.ACCEPTED

    # --- guided setpoints ------------------------------------------------------------------------
    def accepts_setpoints(self) -> bool:
        """GUIDED, armed and flying (or taking off): setpoints are honoured."""
        return self.mode == CopterMode.GUIDED and self.armed and self.submode != "ground"

    def guided_setpoint(self, sp: GuidedSetpoint, stamp_ms: int) -> bool:
        """A decoded SET_POSITION_TARGET_LOCAL_NED; False when ignored (not GUIDED, not flying)."""
        if not self.accepts_setpoints():
            return False
        if sp.control != self.control:  # ArduCopter starts the new sub-mode from the vehicle
            self.shaper.reset()
            self.target = replace(self.target, position_m_enu=self.airframe.position_m_enu)
        self.target = merge(sp, self.target, self.hold_position_m_enu())
        self.heading = heading_of(sp, self.wp_yaw_behavior)
        self.control = sp.control
        self._took_setpoint(stamp_ms, "track")
        return True

    def position_target(self, target: Target, stamp_ms: int) -> bool:
        """Position, velocity, acceleration and heading at once (mask ``0x0800``)."""
        sp = GuidedSetpoint("posvelaccel", target.position_m_enu, target.velocity_mps_enu,
                            target.acceleration_mps2_enu, target.yaw_rad, None)  # fmt: skip
        return self.guided_setpoint(sp, stamp_ms)

    def attitude_setpoint(self, sp: AttitudeSetpoint, stamp_ms: int) -> bool:
        """A decoded SET_ATTITUDE_TARGET; False when ignored."""
        if not self.accepts_setpoints():
            return False
        use_thrust = self.thrust_is_thrust
        z = self.airframe.position_m_enu[2]
        if self.attitude_hold is not None and not self.attitude_hold.use_thrust:
            z = self.attitude_hold.climb_z_m
        self.attitude_hold = AttitudeHold(sp, use_thrust, z)
        self._took_setpoint(stamp_ms, "attitude")
        return True

    @property
    def wp_yaw_behavior(self) -> float:
        """WP_YAW_BEHAVIOR: 0 never turns the vehicle on its own."""
        return self.params["WP_YAW_BEHAVIOR"]

    @property
    def thrust_is_thrust(self) -> bool:
        """SET_ATTITUDE_TARGET's thrust is thrust (GUID_OPTIONS bit 3), not a climb rate."""
        return bool(int(self.params["GUID_OPTIONS"]) & GUID_OPTIONS_THRUST_AS_THRUST)

    def _took_setpoint(self, stamp_ms: int, submode: Submode) -> None:
        landed = self.takeoff_owns_ground and self.submode == "takeoff" and self.on_ground
        self.submode = "ground" if landed else submode
        self.takeoff_alt_m = None
        self.last_setpoint_s = self.now_s
        self.setpoint_stamp_ms = stamp_ms
        self.setpoints_received += 1

    def stop_here(self) -> None:
        """An invalid setpoint in GUIDED: brake and hold where the vehicle is (ArduCopter)."""
        if not self.accepts_setpoints():
            return
        self.target = Target(self.airframe.position_m_enu, yaw_rad=self.airframe.attitude_rad[2])
        self.control, self.heading, self.attitude_hold = "pos", Heading(), None
        self.submode = "track"
        self.shaper.reset()

    def hold_position_m_enu(self) -> Vec3:
        """Where a setpoint without a position keeps the vehicle: the current target in flight."""
        if self.submode == "track":
            return self.target.position_m_enu
        return self.airframe.position_m_enu
