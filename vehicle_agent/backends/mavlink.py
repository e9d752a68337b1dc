"""The MAVLink backend: the agent flies a PX4 or ArduPilot vehicle (or ``skyquill sim-mavlink``).

``start`` opens the link, waits for the autopilot's heartbeat (system and component id from it,
ArduPilot or PX4 from its ``autopilot`` field) and asks for position/attitude telemetry at the
control rate. ``takeoff``: ArduPilot -> GUIDED (custom mode 4, MAV_CMD_DO_SET_MODE), arm,
MAV_CMD_NAV_TAKEOFF (param 7: metres above home); PX4 -> stream the current position for a second,
OFFBOARD, arm, then our own climb ramp. ``tick`` streams SET_POSITION_TARGET_LOCAL_NED (p, v, a) or
SET_ATTITUDE_TARGET at ``setpoint_rate_hz``; ``land`` switches to the autopilot's landing mode;
``estop`` force-disarms. ENU inside, LOCAL_NED on the wire (origin ``origin_m_enu``).

Failsafe, never fighting the pilot: a lost heartbeat, a mode or arming change we did not command
(the pilot's switch or the autopilot's own failsafe), a STATUSTEXT naming a failsafe, or a gap in
our setpoint stream longer than the autopilot's timeout stop the stream and set
``VehicleSnapshot.fault``; commands then raise :class:`VehicleFaultError` (except ``estop``).
Refused commands raise :class:`CommandRejectedError` with the autopilot's STATUSTEXT reason.
"""

from __future__ import annotations

import asyncio
import logging
import math
from collections import deque
from collections.abc import Callable
from typing import Any

from vehicle_agent.backends.base import BackendError, BackendMode, Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.backends.mavlink_brush import BrushModel
from vehicle_agent.backends.mavlink_commands import CommandChannel
from vehicle_agent.backends.mavlink_errors import (
    CommandRejectedError,
    LinkLostError,
    UnsupportedAutopilotError,
    VehicleFaultError,
)
from vehicle_agent.backends.mavlink_frames import LocalFrame, ned_to_enu
from vehicle_agent.backends.mavlink_link import MavlinkLink
from vehicle_agent.backends.mavlink_mocap import MocapForwarder, MocapSource
from vehicle_agent.backends.mavlink_setpoints import (
    MAV_FRAME_LOCAL_NED,
    TYPE_MASK_ATTITUDE_ONLY,
    TYPE_MASK_POSITION_VELOCITY_ACCEL,
    AttitudeOuterLoop,
    ned_target,
)
from vehicle_agent.backends.mavlink_settings import MavlinkSettings, settings_from_show
from vehicle_agent.backends.mavlink_state import SEVERITY_WARNING, LinkState
from vehicle_agent.backends.mavlink_url import parse_mavlink_url
from vehicle_agent.motion import Move, plan_move

log = logging.getLogger(__name__)

CMD_NAV_LAND, CMD_NAV_TAKEOFF, CMD_DO_SET_MODE = 21, 22, 176
CMD_ARM_DISARM, CMD_SET_MESSAGE_INTERVAL = 400, 511
FORCE_DISARM = 21196.0
STREAMED = {32: "LOCAL_POSITION_NED", 30: "ATTITUDE", 85: "POSITION_TARGET_LOCAL_NED"}
SLOW = {1: "SYS_STATUS", 147: "BATTERY_STATUS", 245: "EXTENDED_SYS_STATE"}
TextHandler = Callable[[int, str], None]


class MavlinkBackend:
    """One autopilot behind the :class:`~vehicle_agent.backends.base.VehicleBackend` protocol."""

    def __init__(
        self,
        settings: MavlinkSettings,
        *,
        on_text: TextHandler | None = None,
        mocap_source: MocapSource | None = None,
        brush: BrushModel | None = None,
    ) -> None:
        self.settings = settings
        self.brush = brush
        """The vehicle's passive brush, modelled from its pose for the snapshot (None: none)."""
        self.frame = LocalFrame(settings.origin_m_enu)
        self.state = LinkState(settings.system_id)
        self.mode: BackendMode = "idle"
        self.fault: str | None = None
        self.events: deque[tuple[int, str]] = deque(maxlen=200)
        """STATUSTEXTs of the autopilot (severity, text), newest last, for the event log."""
        self.setpoints_sent = 0
        self._on_text = on_text
        self._mocap = MocapForwarder(settings, self.frame, mocap_source)
        self._link: MavlinkLink | None = None
        self._heartbeat_seen = asyncio.Event()
        self.commands = CommandChannel(lambda: self.link, self.state,
            timeout_s=settings.command_timeout_s, attempts=settings.command_attempts)  # fmt: skip
        self._now_s = 0.0
        self._commanded_mode: int | None = None
        self._commanded_at = 0  # heartbeat count when our last mode/arming change was accepted
        self._hb_count, self._hb_at_s = 0, math.nan
        self._last_tick_s = math.inf
        self._last_sent_s = -math.inf
        self._last_gcs_heartbeat_s = -math.inf
        self._hold: Setpoint | None = None
        self._climb: Move | None = None
        self._climb_to: tuple[Vec3, Vec3] | None = None  # (from, to): planned at the next tick
        self._mode_since_s = math.nan  # NaN: the mode began after the last tick
        self._outer: AttitudeOuterLoop | None = None

    @property
    def control_period_s(self) -> float:
        return self.settings.control_period_s

    @property
    def link(self) -> MavlinkLink:
        if self._link is None:
            raise LinkLostError("MAVLink backend not started")
        return self._link

    # --- connection --------------------------------------------------------------------------
    async def start(self) -> VehicleSnapshot:
        """Open the link and wait for the autopilot's heartbeat."""
        self._link = MavlinkLink(parse_mavlink_url(self.settings.url), self._on_message)
        await self._link.open()
        loop = asyncio.get_running_loop()
        deadline = loop.time() + self.settings.connect_timeout_s
        while not self.state.connected:
            self._send_gcs_heartbeat()
            if loop.time() >= deadline:
                self.close_link()
                raise LinkLostError(
                    f"no autopilot heartbeat on {self.settings.url} within "
                    f"{self.settings.connect_timeout_s:.0f} s"
                )
            try:
                await asyncio.wait_for(self._heartbeat_seen.wait(), timeout=0.5)
            except TimeoutError:
                continue
        if self.state.flavor is None:
            self.close_link()
            raise UnsupportedAutopilotError(
                f"autopilot type {self.state.autopilot} on {self.settings.url} is neither "
                "ArduPilot nor PX4"
            )
        self._request_telemetry()
        if self.state.armed:
            self.fault = "vehicle already armed when the agent connected: the pilot has it"
        log.info("MAVLink vehicle %s (%s) on %s", self.state.system_id,
                 self.state.flavor.name, self.settings.url)  # fmt: skip
        return self._snapshot(0.0)

    def _request_telemetry(self) -> None:
        fast_us = 1e6 / self.settings.telemetry_rate_hz
        for message_id in STREAMED:
            self.commands.send(CMD_SET_MESSAGE_INTERVAL, message_id, fast_us)
        for message_id in SLOW:
            self.commands.send(CMD_SET_MESSAGE_INTERVAL, message_id, 1e6)

    def _on_message(self, message: Any) -> None:
        kind = self.state.absorb(message)
        if kind == "HEARTBEAT":
            self._heartbeat_seen.set()
        elif kind == "COMMAND_ACK":
            self.commands.on_ack(message)
        elif kind == "STATUSTEXT":
            severity, text = self.state.recent_texts[-1]
            self.commands.on_text(text)
            self.events.append((severity, text))
            log.log(logging.WARNING if severity <= SEVERITY_WARNING else logging.INFO,
                    "vehicle %s: %s", self.state.system_id, text)  # fmt: skip
            if self._on_text is not None:
                self._on_text(severity, text)

    # --- commands ----------------------------------------------------------------------------
    async def _set_mode(self, custom_mode: int) -> None:
        flavor = self._flavor()
        await self.commands.run(CMD_DO_SET_MODE, *flavor.set_mode_params(custom_mode))
        self._commanded_mode = custom_mode
        self._commanded_at = self.state.heartbeats

    def _flavor(self) -> Any:
        flavor = self.state.flavor
        if flavor is None:
            raise LinkLostError("no autopilot heartbeat yet")
        return flavor

    def _check_usable(self) -> None:
        if self.fault is not None:
            raise VehicleFaultError(f"vehicle in fault, not commanding it: {self.fault}")

    async def takeoff(self, hover_m_enu: Vec3) -> None:
        """GUIDED/OFFBOARD, arm, climb to ``hover_m_enu``; returns once the climb has begun."""
        self._check_usable()
        if self.mode != "idle":
            raise BackendError(f"cannot take off in mode {self.mode}")
        flavor = self._flavor()
        here = self._position_m_enu()
        if flavor.name == "px4":
            self._hold = Setpoint(position_m_enu=here)
            for _ in range(int(self.settings.setpoint_rate_hz)):  # >1 s of setpoints first
                self._send_setpoint(self._hold, self._now_s)
                await asyncio.sleep(1.0 / self.settings.setpoint_rate_hz)
        await self._set_mode(flavor.offboard_mode)
        await self.commands.run(CMD_ARM_DISARM, 1.0, arming=True)
        self._commanded_at = self.state.heartbeats
        top = (here[0], here[1], hover_m_enu[2])
        if flavor.name == "ardupilot":
            try:
                await self.commands.run(
                    CMD_NAV_TAKEOFF, *([0.0] * 6), top[2] - self.frame.origin_m_enu[2]
                )
            except CommandRejectedError:
                await self._disarm_on_ground()
                raise
            self._climb = None
        else:
            self._climb_to = (here, top)
        self._hold = Setpoint(position_m_enu=hover_m_enu)
        self._set_backend_mode("takeoff")

    async def _disarm_on_ground(self) -> None:
        """Armed but refused the take-off: disarm (best effort) so that it may be retried."""
        try:
            await self.commands.run(CMD_ARM_DISARM, 0.0)
            self._commanded_at = self.state.heartbeats
        except BackendError as exc:
            log.warning("vehicle %s: disarm after a refused take-off: %s",
                        self.state.system_id, exc)  # fmt: skip

    async def land(self) -> None:
        """The autopilot's landing mode (ArduPilot LAND, PX4 AUTO.LAND) where the vehicle is."""
        self._check_usable()
        if self.mode in ("idle", "estop", "landing"):
            return
        await self._set_mode(self._flavor().land_mode)
        self._set_backend_mode("landing")

    async def estop(self) -> None:
        """Force-disarm now (motors off); best effort, never raises for a silent vehicle."""
        self._set_backend_mode("estop")
        if self._link is None or not self.state.connected:
            return
        try:
            await self.commands.run(CMD_ARM_DISARM, 0.0, FORCE_DISARM)
        except BackendError as exc:
            log.error("estop of vehicle %s not confirmed: %s", self.state.system_id, exc)

    def close_link(self) -> None:
        self.commands.cancel_all()
        if self._link is not None:
            self._link.close()
            self._link = None

    async def close(self) -> None:
        """Stop streaming and close the link; safe to call twice."""
        self.close_link()

    # --- the tick ----------------------------------------------------------------------------
    async def tick(self, setpoint: Setpoint | None, now_s: float) -> VehicleSnapshot:
        """Supervise, advance our mode, stream one setpoint when due; the state read back."""
        self._now_s = now_s
        self._supervise(now_s)
        if self.fault is None and self._link is not None:
            self._advance(now_s)
            self._stream(setpoint, now_s)
            self._mocap.forward(self.link, self.state, now_s)
        elif self.state.heartbeats > self._commanded_at:
            self._observe_after_fault()
        if now_s - self._last_gcs_heartbeat_s >= 1.0:
            self._last_gcs_heartbeat_s = now_s
            self._send_gcs_heartbeat()
        return self._snapshot(now_s)

    def _send_gcs_heartbeat(self) -> None:
        if self._link is not None:
            # MAV_TYPE_ONBOARD_CONTROLLER, MAV_AUTOPILOT_INVALID, MAV_STATE_ACTIVE
            self._link.send(self._link.mav.heartbeat_encode(18, 8, 0, 0, 4))

    def _set_backend_mode(self, mode: BackendMode) -> None:
        self.mode = mode
        self._mode_since_s = math.nan

    def _fail(self, reason: str) -> None:
        """Stop streaming for good; the autopilot (or the pilot) flies from here."""
        if self.fault is None:
            self.fault = reason
            log.error("vehicle %s fault: %s", self.state.system_id, reason)
            if self.mode in ("takeoff", "offboard"):
                self._set_backend_mode("hold")

    def _observe_after_fault(self) -> None:
        """In a fault we only watch: a vehicle landed and disarmed (by its pilot) is idle."""
        st = self.state
        on_ground = st.landed_state == 1 if st.landed_state is not None else True
        if self.mode != "estop" and not st.armed and on_ground:
            self._set_backend_mode("idle")

    def _supervise(self, now_s: float) -> None:
        st = self.state
        stalled_s = now_s - self._last_tick_s - self.control_period_s
        if stalled_s > 2 * self.control_period_s:
            # The agent did not run (its clock jumped ahead): we did not listen either, and what
            # the vehicle said meanwhile is still in the socket. Only count time we listened.
            self._hb_at_s += stalled_s
        self._last_tick_s = now_s
        if st.heartbeats != self._hb_count or math.isnan(self._hb_at_s):
            self._hb_count, self._hb_at_s = st.heartbeats, now_s
        silent_s = now_s - self._hb_at_s
        if silent_s > self.settings.heartbeat_timeout_s:
            self._fail(f"lost link: no heartbeat from the autopilot for {silent_s:.1f} s")
        flying = self.mode in ("takeoff", "hold", "offboard", "landing")
        for severity, text in st.take_texts():
            if flying and severity <= SEVERITY_WARNING and "failsafe" in text.lower():
                self._fail(f"autopilot failsafe: {text}")
        fresh = st.heartbeats > self._commanded_at
        if flying and fresh and st.custom_mode != self._commanded_mode:
            name = self._flavor().mode_name(st.custom_mode or 0)
            self._fail(f"mode changed to {name} by the pilot or the autopilot: not streaming")
        if flying and fresh and not st.armed and self.mode != "landing":
            self._fail("vehicle disarmed in flight by the pilot or the autopilot")
        timeout = self.settings.setpoint_timeout_s or self._flavor().setpoint_timeout_s
        gap_s = now_s - self._last_sent_s
        if self.mode in ("hold", "offboard") and gap_s > timeout:
            self._fail(f"setpoint stream stopped for {gap_s:.1f} s (autopilot timeout "
                       f"{timeout:.1f} s): its failsafe has stopped the vehicle")  # fmt: skip
        self._check_progress(now_s)

    def _check_progress(self, now_s: float) -> None:
        if math.isnan(self._mode_since_s):
            self._mode_since_s = now_s
        in_mode_s = now_s - self._mode_since_s
        if self.mode == "takeoff" and in_mode_s > self.settings.takeoff_timeout_s:
            self._fail(f"take-off not complete after {in_mode_s:.0f} s")
        if self.mode == "landing" and in_mode_s > self.settings.land_timeout_s:
            self._fail(f"landing not complete after {in_mode_s:.0f} s")

    def _advance(self, now_s: float) -> None:
        st = self.state
        if self._climb_to is not None:
            start, top = self._climb_to
            self._climb = plan_move(start, top, now_s, v_max_mps=self.settings.climb_speed_mps,
                                    a_max_mps2=0.8)  # fmt: skip
            self._climb_to = None
        if self.mode == "takeoff" and self._hold is not None:
            climb_done = self._climb is None or self._climb.done(now_s)
            height_error = abs(self._position_m_enu()[2] - self._hold.position_m_enu[2])
            near = height_error < self.settings.takeoff_tolerance_m
            if climb_done and st.position_ned is not None and near:
                self._climb = None
                self._set_backend_mode("hold")
        elif self.mode == "landing" and not st.armed and st.heartbeats > self._commanded_at:
            self._set_backend_mode("idle")
            self._hold = None

    def _stream(self, setpoint: Setpoint | None, now_s: float) -> None:
        if setpoint is not None and self.mode in ("takeoff", "hold", "offboard"):
            self._climb, self._climb_to = None, None
            if self.mode != "offboard":
                self._set_backend_mode("offboard")
            self._hold = Setpoint(position_m_enu=setpoint.position_m_enu)
            target = setpoint
        elif self.mode in ("hold", "offboard") and self._hold is not None:
            if self.mode == "offboard":
                self._set_backend_mode("hold")
            target = self._hold
        elif self.mode == "takeoff" and self._climb is not None:
            target = self._climb.setpoint(now_s)
        else:
            return
        if (
            self.settings.setpoints == "attitude"
            or now_s - self._last_sent_s >= self._send_period_s()
        ):
            self._send_setpoint(target, now_s)

    def _send_period_s(self) -> float:
        return 1.0 / self.settings.setpoint_rate_hz - 0.5 * self.control_period_s

    def _send_setpoint(self, setpoint: Setpoint, now_s: float) -> None:
        st, mav = self.state, self.link.mav
        stamp_ms = int(now_s * 1000) & 0xFFFFFFFF
        sysid, compid = st.system_id or 0, st.component_id or 0
        if self.settings.setpoints == "attitude":
            command = self._attitude_loop().update(self._position_m_enu(), setpoint)
            if now_s - self._last_sent_s < self._send_period_s():
                return  # the outer loop runs every tick; the stream goes at its own rate
            message = mav.set_attitude_target_encode(stamp_ms, sysid, compid,
                TYPE_MASK_ATTITUDE_ONLY, command.q_ned, 0.0, 0.0, 0.0, command.thrust)  # fmt: skip
        else:
            t = ned_target(setpoint, self.frame)
            message = mav.set_position_target_local_ned_encode(
                stamp_ms, sysid, compid, MAV_FRAME_LOCAL_NED, TYPE_MASK_POSITION_VELOCITY_ACCEL,
                *t.position_m_ned, *t.velocity_mps_ned, *t.acceleration_mps2_ned, 0.0, 0.0,
            )  # fmt: skip
        if self.link.send(message):
            self._last_sent_s = now_s
            self.setpoints_sent += 1

    def _attitude_loop(self) -> AttitudeOuterLoop:
        if self._outer is None:
            s = self.settings
            thrust_max_mps2 = s.thrust_max_n / s.mass_kg
            self._outer = AttitudeOuterLoop(
                s.controller, s.control_period_s, self._position_m_enu(), thrust_max_mps2
            )
        return self._outer

    # --- state out ---------------------------------------------------------------------------
    def _position_m_enu(self) -> Vec3:
        ned = self.state.position_ned
        return self.frame.origin_m_enu if ned is None else self.frame.position_from_ned(ned)

    def _snapshot(self, now_s: float) -> VehicleSnapshot:
        st = self.state
        on_ground = st.landed_state == 1 if st.landed_state is not None else not st.armed
        position = self._position_m_enu()
        brush = None
        if self.brush is not None and st.attitude_ned is not None:
            brush = self.brush.read(position, st.attitude_ned)
        return VehicleSnapshot(
            t_s=now_s,
            position_m_enu=position,
            velocity_mps_enu=ned_to_enu(st.velocity_ned),
            armed=st.armed,
            mode=self.mode,
            on_ground=on_ground,
            battery_fraction=st.battery_fraction,
            fault=self.fault,
            pen_tip_m_enu=None if brush is None else brush.tip_m_enu,
            pen_width_m=None if brush is None else brush.width_m,
            pen_contact=None if brush is None else brush.contact,
        )


def create_backend(setup: Any, **kwargs: Any) -> MavlinkBackend:
    """The backend of ``setup`` (a :class:`vehicle_agent.agent.VehicleSetup` whose vehicle has
    ``backend: mavlink``), carrying the show's brush over its board; ``kwargs`` go to
    :class:`MavlinkBackend` (``on_text``, ``mocap_source``)."""
    from vehicle_agent.agent import on_board, world_params  # the agent imports us lazily

    show = setup.show
    settings = settings_from_show(show, show.vehicle(setup.vehicle_id))
    world = world_params(setup)
    kwargs.setdefault("brush", BrushModel(world.brush, world.board_height_m, on_board(setup)))
    return MavlinkBackend(settings, **kwargs)
