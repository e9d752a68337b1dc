"""The MAVLink backend: the agent flies a PX4 or ArduPilot vehicle (or ``skyquill sim-mavlink``).

Built from a show's vehicle by :func:`~vehicle_agent.backends.mavlink.create.create_backend`.
``start`` opens the link and connects (:mod:`~vehicle_agent.backends.mavlink.connect`: our
ground-station heartbeat, the autopilot's, the telemetry asked for, the show's parameters set and
read back; if they do not hold, the vehicle is in fault).
``takeoff``: ArduPilot -> GUIDED (custom mode 4, MAV_CMD_DO_SET_MODE), arm, MAV_CMD_NAV_TAKEOFF
(param 7: metres above home); PX4 -> stream setpoints for a second, OFFBOARD, arm, then our own
climb ramp; not while SYS_STATUS says the pre-arm checks fail: then nothing is sent and the
refusal carries the autopilot's words (asked for with MAV_CMD_RUN_PREARM_CHECKS if unsaid).
``tick`` streams SET_POSITION_TARGET_LOCAL_NED (p, v, a and the take-off heading) or
SET_ATTITUDE_TARGET at ``setpoint_rate_hz``; ``land`` switches to the autopilot's landing mode;
``estop`` force-disarms; ``recover`` makes a vehicle at rest ``idle`` again (the commands:
:mod:`~vehicle_agent.backends.mavlink.flight_commands`). ENU inside, LOCAL_NED on the wire
(origin ``origin_m_enu``).

Failsafe, never fighting the pilot (:mod:`~vehicle_agent.backends.mavlink.watchdog`): a lost
heartbeat, a mode or arming change we did not command, a STATUSTEXT naming a failsafe, or a gap in
our setpoint stream longer than the autopilot's timeout stop the stream and set
``VehicleSnapshot.fault``; commands then raise :class:`VehicleFaultError` (except ``estop``).
Refused commands raise :class:`CommandRejectedError` with the autopilot's STATUSTEXT reason.
"""

from __future__ import annotations

import asyncio
import logging
import math
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from vehicle_agent.backends.base import BackendError, BackendMode, Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.backends.mavlink.battery import reset_after_swap
from vehicle_agent.backends.mavlink.commands import CommandChannel
from vehicle_agent.backends.mavlink.connect import (
    GCS_HEARTBEAT_PERIOD_S,
    await_autopilot,
    request_telemetry,
    send_gcs_heartbeat,
    set_show_params,
)
from vehicle_agent.backends.mavlink.errors import (
    LinkLostError,
    UnsupportedAutopilotError,
    VehicleFaultError,
)
from vehicle_agent.backends.mavlink.flight_commands import (
    FlightCommands,
    disarmed_on_ground,
    refuse_recovery,
)
from vehicle_agent.backends.mavlink.frames import LocalFrame
from vehicle_agent.backends.mavlink.health import fence_problem, link_health
from vehicle_agent.backends.mavlink.home import HomeSetter
from vehicle_agent.backends.mavlink.link import MavlinkLink
from vehicle_agent.backends.mavlink.mocap import MocapForwarder, MocapSource, TickTime
from vehicle_agent.backends.mavlink.params import ParamChannel
from vehicle_agent.backends.mavlink.pen import PenOverBoard
from vehicle_agent.backends.mavlink.response import ResponseAid
from vehicle_agent.backends.mavlink.settings import MavlinkSettings
from vehicle_agent.backends.mavlink.snapshot import off_the_mocap_m, pen_reading, vehicle_snapshot
from vehicle_agent.backends.mavlink.state import SEVERITY_WARNING, LinkState
from vehicle_agent.backends.mavlink.stream import SetpointStream
from vehicle_agent.backends.mavlink.takeoff_checks import (
    PrearmAsker,
    heading_ned_rad,
    prove_life,
    refuse_off_the_mocap,
    refuse_while_prearm_fails,
)
from vehicle_agent.backends.mavlink.truth import TRUTH_KINDS
from vehicle_agent.backends.mavlink.url import parse_mavlink_url
from vehicle_agent.backends.mavlink.watchdog import Commanded, Watchdog, WatchLimits
from vehicle_agent.motion import Move, plan_move

log = logging.getLogger(__name__)

TextHandler = Callable[[int, str], None]


class MavlinkBackend:
    """One autopilot behind the :class:`~vehicle_agent.backends.base.VehicleBackend` protocol."""

    def __init__(
        self,
        settings: MavlinkSettings,
        *,
        on_text: TextHandler | None = None,
        mocap_source: MocapSource | None = None,
        pen: PenOverBoard | None = None,
    ) -> None:
        self.settings = settings
        self.pen = pen
        """The vehicle's pen, modelled from its pose for the snapshot (None: none)."""
        self.frame = LocalFrame(settings.origin_m_enu)
        self.state = LinkState(settings.system_id)
        self.mode: BackendMode = "idle"
        self.fault: str | None = None
        self.events: deque[tuple[int, str]] = deque(maxlen=200)
        """STATUSTEXTs of the autopilot (severity, text), newest last, for the event log."""
        self._on_text = on_text
        self.aid = ResponseAid(settings, seed=settings.system_id or 0)
        """The vehicle's true state (SITL) and its identified lag."""
        source = mocap_source if mocap_source is not None else self.aid.mocap_source()
        self._mocap = MocapForwarder(settings, self.frame, source, lambda: self._flavor().name)
        self.tick_time = TickTime()
        """The agent's clock between ticks (truth stamps, mocap)."""
        self._link: MavlinkLink | None = None
        self._heartbeat_seen = asyncio.Event()
        self.commands = CommandChannel(lambda: self.link, self.state,
            timeout_s=settings.command_timeout_s, attempts=settings.command_attempts)  # fmt: skip
        self.params = ParamChannel(lambda: self.link, self.state, lambda: self._flavor().name,
            timeout_s=settings.command_timeout_s, attempts=settings.command_attempts)  # fmt: skip
        self.params_set: dict[str, float] = {}
        """Parameters set and read back at connect, by name."""
        limits = WatchLimits(settings.heartbeat_timeout_s, settings.setpoint_timeout_s,
                             settings.takeoff_timeout_s, settings.land_timeout_s)  # fmt: skip
        self.watchdog = Watchdog(limits)
        self._now_s = 0.0
        self.flight = FlightCommands(self.state, self.commands, self._flavor)
        """Mode changes and arming, and the record of them the watchdog reads."""
        self._last_gcs_heartbeat_s = -math.inf
        self._prearm = PrearmAsker(self.state, self.commands)
        self._home = HomeSetter(self.commands)
        self._hold: Setpoint | None = None
        self._climb: Move | None = None
        self._climb_to: tuple[Vec3, Vec3] | None = None  # (from, to): planned at the next tick
        self.stream = SetpointStream(settings, self.frame, self.state, lambda: self.link)

    @property
    def control_period_s(self) -> float:
        return self.settings.control_period_s

    @property
    def setpoints_sent(self) -> int:
        """Setpoints sent so far."""
        return self.stream.sent

    @property
    def link(self) -> MavlinkLink:
        if self._link is None:
            raise LinkLostError("MAVLink backend not started")
        return self._link

    # --- connection --------------------------------------------------------------------------
    async def start(self) -> VehicleSnapshot:
        """Open the link and wait for the autopilot's heartbeat."""
        s = self.settings
        self._link = MavlinkLink(parse_mavlink_url(s.url), self._on_message)
        await self._link.open()
        try:
            await await_autopilot(self.state, self._heartbeat_seen, self._send_gcs_heartbeat,
                                  url=s.url, timeout_s=s.connect_timeout_s)  # fmt: skip
        except (LinkLostError, UnsupportedAutopilotError):
            self.close_link()
            raise
        flavor = self._flavor().name
        request_telemetry(
            self.commands, s.telemetry_rate_hz, self.aid.truth_message(flavor), flavor
        )
        # also after a fault: the autopilot (or the pilot) still flies on the mocap
        self._mocap.start(lambda: self._link, self.tick_time)
        if self.state.armed:
            self.fault = "vehicle already armed when the agent connected: the pilot has it"
        else:
            if s.set_params:
                fault = await set_show_params(self.params, s, self._flavor().name, self.params_set)
                if fault is not None:
                    self.fault = fault
                    log.error("vehicle %s: %s", self.state.system_id, fault)
            if self._flavor().name == "px4":  # ArduPilot: once it says it uses external nav
                self._mocap.set_ekf_origin(self.link, self.state.system_id or 0)
        log.info("MAVLink vehicle %s (%s) on %s", self.state.system_id,
                 self._flavor().name, s.url)  # fmt: skip
        return self._snapshot(0.0)

    def _on_message(self, message: Any) -> None:
        kind = self.state.absorb(message)
        if kind == "HEARTBEAT":
            self._heartbeat_seen.set()
        elif kind == "COMMAND_ACK":
            self.commands.on_ack(message)
        elif kind == "PARAM_VALUE":
            self.params.on_param_value(message)
        elif kind in TRUTH_KINDS:
            now_s = self.tick_time.now_s(time.monotonic())
            self.aid.on_message(message, now_s, resting_at_home=not self.state.armed,
                                autopilot_time_ms=self.state.attitude_time_ms)  # fmt: skip
        elif kind == "STATUSTEXT":
            self._tell_texts()

    def _tell_texts(self) -> None:
        """Hand on the autopilot's texts completed since the last time (chunks joined: two at
        once when a cut-off one is followed by another, a late part from ``tick``)."""
        for severity, text in self.state.take_to_tell():
            self.commands.on_text(text)
            self.events.append((severity, text))
            if "using external nav" in text and self._link is not None:
                self._mocap.set_ekf_origin(self._link, self.state.system_id or 0)
            log.log(logging.WARNING if severity <= SEVERITY_WARNING else logging.INFO,
                    "vehicle %s: %s", self.state.system_id, text)  # fmt: skip
            if self._on_text is not None:
                self._on_text(severity, text)

    # --- commands ----------------------------------------------------------------------------
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
        await refuse_while_prearm_fails(self.state, self.commands)
        flavor = self._flavor()
        here = self._position_m_enu()
        refuse_off_the_mocap(here, self._mocap.position_m_enu)
        self.stream.new_flight(await heading_ned_rad(self.state))
        self.aid.lag.reset()
        if flavor.name == "px4":
            self._hold = Setpoint(position_m_enu=here)
            await prove_life(self.stream, self._hold, self.settings.setpoint_rate_hz,
                             self._now_s, self._send_gcs_heartbeat)  # fmt: skip
        top = (here[0], here[1], hover_m_enu[2])
        await self.flight.take_off(flavor, top[2] - self.frame.origin_m_enu[2])
        if flavor.name == "ardupilot":
            self._climb = None
        else:
            self._climb_to = (here, top)
        self._hold = Setpoint(position_m_enu=hover_m_enu)
        self._set_backend_mode("takeoff")

    async def land(self) -> None:
        """The autopilot's landing mode (ArduPilot LAND, PX4 AUTO.LAND) where the vehicle is."""
        self._check_usable()
        if self.mode in ("idle", "estop", "landing"):
            return
        await self.flight.land()
        self._set_backend_mode("landing")

    async def estop(self) -> None:
        """Force-disarm now (motors off); best effort, never raises for a silent vehicle."""
        self._set_backend_mode("estop")
        if self._link is not None and self.state.connected:
            await self.flight.force_disarm()

    async def recover(self) -> None:
        """After an e-stop (a force-disarm) or a fault: ``idle`` again once the autopilot, heard
        within its heartbeat timeout, says it is disarmed on the ground. Nothing is sent: the
        next take-off sets the mode and arms through the autopilot's own pre-arm checks."""
        refuse_recovery(self.state, linked=self._link is not None,
                        silent_s=self.watchdog.link_silent_s(self._now_s),
                        heartbeat_timeout_s=self.settings.heartbeat_timeout_s)  # fmt: skip
        if self.fault is not None:
            log.warning("vehicle %s: fault cleared by the operator: %s",
                        self.state.system_id, self.fault)  # fmt: skip
        self.fault, self._hold, self._climb, self._climb_to = None, None, None, None
        self.flight.heard()
        self._set_backend_mode("idle")

    async def swap_battery(self) -> None:
        """The crew's fresh pack, told to the autopilot where it keeps a count
        (:mod:`~vehicle_agent.backends.mavlink.battery`)."""
        await reset_after_swap(self.commands, self.state)

    def close_link(self) -> None:
        self._mocap.stop()
        self._home.cancel()
        self.commands.cancel_all()
        self.params.cancel_all()
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
        self.tick_time.ticked(now_s, time.monotonic())
        self._supervise(now_s)
        self._tell_texts()  # the part of a chunked text that waited its time for the rest
        if self._link is not None:
            self._prearm.ask_why_not_ready(now_s)
        measure = False
        if self.fault is None and self._link is not None:
            self._advance(now_s)
            measure = self._stream(setpoint, now_s)
        elif self.state.heartbeats > self.flight.commanded_at:
            self._observe_after_fault()
        if now_s - self._last_gcs_heartbeat_s >= GCS_HEARTBEAT_PERIOD_S:
            self._last_gcs_heartbeat_s = now_s
            self._send_gcs_heartbeat()
        return self._snapshot(now_s, measure=measure)

    def _send_gcs_heartbeat(self) -> None:
        if self._link is not None:
            send_gcs_heartbeat(self._link)

    def _set_backend_mode(self, mode: BackendMode) -> None:
        self.mode = mode
        self.watchdog.mode_changed()
        self.flight.stop_asking_ground_mode()

    def _fail(self, reason: str) -> None:
        """Stop streaming for good; the autopilot (or the pilot) flies from here."""
        if self.fault is None:
            self.fault = reason
            log.error("vehicle %s fault: %s", self.state.system_id, reason)
            if self.mode in ("takeoff", "offboard"):
                self._set_backend_mode("hold")

    def _observe_after_fault(self) -> None:
        """In a fault we only watch: a vehicle landed and disarmed (by its pilot) is idle."""
        if self.mode != "estop" and disarmed_on_ground(self.state):
            self._set_backend_mode("idle")

    def _supervise(self, now_s: float) -> None:
        flight = self.flight
        commanded = Commanded(flight.commanded_mode, flight.commanded_at, self.stream.last_sent_s)
        reason = self.watchdog.check(now_s, self.control_period_s, self.state, self._flavor(),
                                     self.mode, commanded)  # fmt: skip
        if reason is not None:
            self._fail(reason)

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
                if self._climb is not None:  # our own climb (PX4): its outer loop learnt the
                    self.stream.new_flight(self.stream.heading_ned_rad)  # ground; start afresh
                self._climb = None
                self._set_backend_mode("hold")
        elif self.mode == "landing":
            if self.flight.landing_over(now_s):
                self._set_backend_mode("idle")
                self._hold = None
        elif self.mode == "idle":
            if st.in_offboard_on_ground:  # a refused arming, or found so at connect
                self.flight.ask_ground_mode(now_s, math.inf)
            self._home.step(now_s, self._home_ready)

    def _home_ready(self) -> bool:
        """A PX4 on the EKF origin we gave it, disarmed on the ground, its estimate on the
        mocap: its home can be put where it stands (:mod:`~vehicle_agent.backends.mavlink.home`)."""
        st, mocap_m_enu = self.state, self._mocap.position_m_enu
        if st.flavor is None or st.flavor.name != "px4" or not self._mocap.origin_sent:
            return False
        if mocap_m_enu is None or st.position_ned is None or not disarmed_on_ground(st):
            return False
        return off_the_mocap_m(self._position_m_enu(), mocap_m_enu) is None

    def _stream(self, setpoint: Setpoint | None, now_s: float) -> bool:
        """Send our mode's setpoint; True: the lag is to measure where the pen writes now."""
        if setpoint is not None and self.mode in ("takeoff", "hold", "offboard"):
            self._climb, self._climb_to = None, None
            if self.mode != "offboard":
                self._set_backend_mode("offboard")
            self._hold = Setpoint(position_m_enu=setpoint.position_m_enu)
            target = self.aid.lead(setpoint, now_s)
        elif self.mode in ("hold", "offboard") and self._hold is not None:
            if self.mode == "offboard":
                self._set_backend_mode("hold")
            target = self._hold
        elif self.mode == "takeoff" and self._climb is not None:
            target = self._climb.setpoint(now_s)
        else:
            return False
        sent = self.stream.sent
        self.stream.send(target, now_s)
        if self.mode not in ("hold", "offboard") or self.state.position_ned is None:
            return False
        if self.stream.sent > sent:
            self.aid.sent(now_s, target.position_m_enu)
        return True

    # --- state out ---------------------------------------------------------------------------
    def _position_m_enu(self) -> Vec3:
        ned = self.state.position_ned
        return self.frame.origin_m_enu if ned is None else self.frame.position_from_ned(ned)

    def _snapshot(self, now_s: float, *, measure: bool = False) -> VehicleSnapshot:
        """The vehicle now; ``measure``: the lag measures where the pen writes, as read here."""
        position, truth = self._position_m_enu(), self.aid.true_state(now_s)
        reading = pen_reading(self.pen, position, self.state.attitude_ned, truth)
        if measure:
            self.aid.measured(now_s, position, truth, reading)
        asked = self.settings.fence is not None
        fence = fence_problem(asked, self.settings.set_params, self.params_set, self._flavor().name)
        losses = None if self._link is None else self._link.losses
        health = link_health(self.state, losses, self.watchdog.link_silent_s(now_s),
                             self._mocap.age_s(now_s), fence)  # fmt: skip
        return vehicle_snapshot(self.state, now_s, position, truth, mode=self.mode,
                                fault=self.fault, reading=reading, health=health,
                                mocap_m_enu=self._mocap.position_m_enu)  # fmt: skip
