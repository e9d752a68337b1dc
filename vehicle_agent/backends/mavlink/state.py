"""What the autopilot told us, absorbed message by message (pure: no I/O; the one clock, for how
long part of a chunked STATUSTEXT waits for the rest, is given to :class:`LinkState`).

:class:`Flavor` captures the two autopilots' mode encodings: ArduPilot's HEARTBEAT ``custom_mode``
is the mode number (GUIDED 4, LAND 9); PX4's is ``main << 16 | sub << 24`` (OFFBOARD main 6,
AUTO.LAND main 4 sub 6) and MAV_CMD_DO_SET_MODE takes main and sub in params 2 and 3.
:class:`StatustextJoiner` makes one text of a STATUSTEXT sent in chunks (PX4, over 50 characters).
"""

from __future__ import annotations

import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

from vehicle_agent.backends.mavlink.frames import Vec3

MAV_AUTOPILOT_ARDUPILOTMEGA = 3
MAV_AUTOPILOT_INVALID = 8
MAV_AUTOPILOT_PX4 = 12
MAV_TYPE_GCS = 6
MAV_MODE_FLAG_SAFETY_ARMED = 128
UNKNOWN_MV = 65535
"""UINT16_MAX: a voltage the autopilot does not send (BATTERY_STATUS cells, SYS_STATUS)."""
SEVERITY_WARNING = 4
STATUSTEXT_CHARS = 50
"""Characters in one STATUSTEXT's ``text`` (common.xml: char[50]); a chunk this full may go on."""
STATUSTEXT_JOIN_WAIT_S = 1.0
"""How long in [s] part of a chunked STATUSTEXT waits for its next chunk before it is handed on as
it is. PX4 sends all the chunks of a text in one pass of its STATUSTEXT stream
(``src/modules/mavlink/streams/STATUSTEXT.hpp``), so they arrive together: the wait is for a chunk
lost on the link, and for a text of exactly 50, 100... characters, whose last chunk is full."""

_ARDUPILOT_MODES = {0: "STABILIZE", 2: "ALT_HOLD", 3: "AUTO", 4: "GUIDED", 5: "LOITER", 6: "RTL",
                    9: "LAND", 16: "POSHOLD", 17: "BRAKE", 20: "GUIDED_NOGPS"}  # fmt: skip
_PX4_MAIN = {1: "MANUAL", 2: "ALTCTL", 3: "POSCTL", 4: "AUTO", 5: "ACRO", 6: "OFFBOARD",
             7: "STABILIZED", 8: "RATTITUDE"}  # fmt: skip
_PX4_AUTO = {1: "READY", 2: "TAKEOFF", 3: "LOITER", 4: "MISSION", 5: "RTL", 6: "LAND"}


@dataclass(frozen=True)
class Flavor:
    """How one autopilot family encodes the modes we use."""

    name: Literal["ardupilot", "px4"]
    """Autopilot family."""
    offboard_mode: int
    """HEARTBEAT custom_mode of the mode that follows our setpoints (GUIDED / OFFBOARD)."""
    land_mode: int
    """HEARTBEAT custom_mode of the autopilot's landing mode."""
    setpoint_timeout_s: float
    """Default time without setpoints after which the autopilot stops following us [s]
    (ArduPilot GUID_TIMEOUT 3 s; PX4 COM_OF_LOSS_T 1 s)."""
    ground_mode: int | None = None
    """HEARTBEAT custom_mode to put the vehicle in once it has landed and disarmed (None: leave
    it in the landing mode). PX4: AUTO.LOITER (Hold), because after a landing it goes back to
    OFFBOARD, where its pre-arm bit stays clear until setpoints stream; in Hold the bit says
    what its checks say (SYS_STATUS.hpp: ``can_arm_mode_flags`` of the current ``nav_state``)."""

    def set_mode_params(self, custom_mode: int) -> tuple[float, float, float]:
        """(param1, param2, param3) of MAV_CMD_DO_SET_MODE for ``custom_mode``."""
        if self.name == "px4":
            return (1.0, float((custom_mode >> 16) & 0xFF), float((custom_mode >> 24) & 0xFF))
        return (1.0, float(custom_mode), 0.0)

    def mode_name(self, custom_mode: int) -> str:
        """Human name of a HEARTBEAT custom_mode."""
        if self.name == "px4":
            main, sub = (custom_mode >> 16) & 0xFF, (custom_mode >> 24) & 0xFF
            name = _PX4_MAIN.get(main, f"MAIN{main}")
            return f"{name}.{_PX4_AUTO.get(sub, sub)}" if main == 4 else name
        return _ARDUPILOT_MODES.get(custom_mode, f"MODE{custom_mode}")


ARDUPILOT = Flavor("ardupilot", offboard_mode=4, land_mode=9, setpoint_timeout_s=3.0)
PX4 = Flavor(
    "px4",
    offboard_mode=6 << 16,
    land_mode=(4 << 16) | (6 << 24),
    setpoint_timeout_s=1.0,
    ground_mode=(4 << 16) | (3 << 24),
)


def flavor_for(autopilot: int) -> Flavor | None:
    """The flavor of a HEARTBEAT ``autopilot`` field, None when unsupported."""
    return {MAV_AUTOPILOT_ARDUPILOTMEGA: ARDUPILOT, MAV_AUTOPILOT_PX4: PX4}.get(autopilot)


@dataclass
class _PartialText:
    """The chunks of one STATUSTEXT received so far."""

    severity: int
    text_id: int
    next_chunk: int
    """The ``chunk_seq`` that would continue it."""
    parts: list[str]
    last_chunk_s: float
    """When its last chunk arrived, in [s] (the caller's clock)."""


class StatustextJoiner:
    """One text from the STATUSTEXTs it was sent in (pure: the time is given).

    MAVLink 2 sends a text longer than 50 characters as STATUSTEXTs with the same ``id`` and
    ``chunk_seq`` 0, 1, 2...; the last is shorter than 50 (NUL-terminated). ``id`` 0 means a text
    of one chunk (common.xml), as ArduPilot (GCS_Common.cpp numbers chunked texts from 1) and
    mavsim send it; but PX4 numbers its texts from 0 on each link (``_id++`` in STATUSTEXT.hpp),
    so its first text, if longer, comes as id 0 in chunks: with ``zero_chunks`` (PX4) an id-0
    text that fills its 50 characters waits like any chunk, and one that says ``chunk_seq`` 1
    goes on it. Part of a text is handed on as it is when a chunk of another text
    (or out of sequence) arrives, or once it has waited :data:`STATUSTEXT_JOIN_WAIT_S`: no words
    are lost to a chunk that never comes.
    """

    def __init__(self, wait_s: float = STATUSTEXT_JOIN_WAIT_S) -> None:
        self.wait_s = wait_s
        self._partial: _PartialText | None = None

    def add(
        self,
        severity: int,
        text: str,
        text_id: int,
        chunk_seq: int,
        now_s: float,
        *,
        zero_chunks: bool = False,
    ) -> list[tuple[int, str]]:
        """The texts (severity, text), oldest first, that are whole once this chunk is in:
        usually none (it waits for the rest) or one."""
        done = self.expire(now_s)
        partial = self._partial
        if partial is not None and (text_id, chunk_seq) != (partial.text_id, partial.next_chunk):
            done += self._hand_on()
        whole = chunk_seq == 0 and (len(text) < STATUSTEXT_CHARS or not zero_chunks)
        if text_id == 0 and whole:
            return [*done, (severity, text)]
        if self._partial is None:  # chunk_seq > 0: its beginning was lost, the rest still joins
            self._partial = _PartialText(severity, text_id, chunk_seq, [], now_s)
        self._partial.parts.append(text)
        self._partial.next_chunk += 1
        self._partial.last_chunk_s = now_s
        if len(text) < STATUSTEXT_CHARS:
            done += self._hand_on()
        return done

    def expire(self, now_s: float) -> list[tuple[int, str]]:
        """The part of a text that has waited too long for its next chunk (or nothing)."""
        partial = self._partial
        if partial is not None and now_s - partial.last_chunk_s >= self.wait_s:
            return self._hand_on()
        return []

    def _hand_on(self) -> list[tuple[int, str]]:
        partial, self._partial = self._partial, None
        return [] if partial is None else [(partial.severity, "".join(partial.parts))]


class LinkState:
    """Latest vehicle state from its messages; counters let callers see what is new."""

    def __init__(
        self,
        system_id: int | None = None,
        *,
        own_system_id: int = 255,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self._clock = clock
        """Time in [s], for how long part of a chunked STATUSTEXT has waited for the rest."""
        self._text_joiner = StatustextJoiner()
        self.own_system_id = own_system_id
        """Our system id: COMMAND_ACKs addressed to another ground station are not ours."""
        self.system_id = system_id
        """The autopilot's system id: configured, or taken from its first HEARTBEAT."""
        self.component_id: int | None = None
        self.autopilot: int | None = None
        self.heartbeats = 0
        self.custom_mode: int | None = None
        self.armed = False
        self.positions = 0
        self.position_ned: Vec3 | None = None
        self.velocity_ned: Vec3 = (0.0, 0.0, 0.0)
        self.position_time_ms = 0
        self.attitude_ned: Vec3 | None = None
        self.attitude_time_ms = 0
        """``time_boot_ms`` of the last ATTITUDE: the autopilot's clock (SITL: the simulator's)."""
        self.battery_fraction: float | None = None
        self.battery_voltage_v: float | None = None
        self.battery_minutes_left: float | None = None
        """BATTERY_STATUS ``time_remaining`` in [min] (None: not sent, or 0: unknown)."""
        self._battery_from_status = False
        self.landed_state: int | None = None
        self.estimator_flags: int | None = None
        """ESTIMATOR_STATUS / EKF_STATUS_REPORT ``flags`` (None: neither sent)."""
        self.prearm_good: bool | None = None
        """SYS_STATUS says the pre-arm checks pass (None: no SYS_STATUS yet)."""
        self.prearm_mode: int | None = None
        """The HEARTBEAT custom_mode as the last SYS_STATUS came (PX4's bit is for that mode)."""
        self.prearm_text: str | None = None
        """The autopilot's latest explanation of a failing pre-arm check (a STATUSTEXT that
        begins as :data:`PREARM_EXPLANATIONS`), forgotten whenever SYS_STATUS says they pass."""
        self.target_stamps = 0
        self.target_stamp_ms: int | None = None
        """``time_boot_ms`` of the last POSITION_TARGET_LOCAL_NED (our stamp, on mavsim)."""
        self.acks: deque[tuple[int, int]] = deque(maxlen=64)
        self.texts: deque[tuple[int, str]] = deque(maxlen=64)
        """STATUSTEXTs (severity, text), chunks joined, not yet taken by :meth:`take_texts`."""
        self.recent_texts: deque[tuple[int, str]] = deque(maxlen=16)
        """The last STATUSTEXTs (chunks joined), newest last."""
        self.to_tell: deque[tuple[int, str]] = deque(maxlen=64)
        """STATUSTEXTs (chunks joined) not yet handed on by :meth:`take_to_tell` (the backend's
        event log, its command refusals), apart from the watchdog's :meth:`take_texts`."""

    @property
    def flavor(self) -> Flavor | None:
        return None if self.autopilot is None else flavor_for(self.autopilot)

    @property
    def preflight(self) -> str | None:
        """Why the autopilot would refuse to arm now, in its own words (:data:`PREARM_UNSAID`
        when it has not said); None while SYS_STATUS says its pre-arm checks pass, or before
        the first SYS_STATUS. PX4 sets the bit for the mode it is in (SYS_STATUS.hpp:
        ``can_arm_mode_flags`` of the current ``nav_state``), and in OFFBOARD on the ground,
        with no setpoints streaming, it is clear whatever the checks say (PX4 goes back to
        OFFBOARD after each landing, measured on 1.16 SIH): then :data:`PX4_OFFBOARD_ON_GROUND`,
        until the agent has it in Hold (:attr:`Flavor.ground_mode`), where the bit means them."""
        flavor = self.flavor
        if self.in_offboard_on_ground and flavor is not None and flavor.ground_mode is not None:
            return PX4_OFFBOARD_ON_GROUND
        if self.prearm_good is not False:
            return None
        return self.prearm_text or PREARM_UNSAID

    @property
    def in_offboard_on_ground(self) -> bool:
        """Disarmed in the mode that follows our setpoints (PX4 after a landing, or after its
        arming was refused there)."""
        flavor = self.flavor
        return flavor is not None and not self.armed and self.custom_mode == flavor.offboard_mode

    @property
    def connected(self) -> bool:
        """A heartbeat of the autopilot was seen."""
        return self.heartbeats > 0

    def take_texts(self) -> list[tuple[int, str]]:
        """The STATUSTEXTs received since the last call, with the part of a chunked one that has
        waited its time for the rest (the watchdog calls this every tick: no text is held long)."""
        self._keep_texts(self._text_joiner.expire(self._clock()))
        texts = list(self.texts)
        self.texts.clear()
        return texts

    def take_to_tell(self) -> list[tuple[int, str]]:
        """The STATUSTEXTs completed since the last call, the part of a chunked one that has
        waited its time for the rest included: every text once, however it came."""
        self._keep_texts(self._text_joiner.expire(self._clock()))
        told = list(self.to_tell)
        self.to_tell.clear()
        return told

    def absorb(self, message: Any) -> str:
        """Take one message into the state; returns its type ("" when ignored: another system,
        or a STATUSTEXT chunk that waits for the rest of its text)."""
        kind: str = message.get_type()
        source = message.get_srcSystem()
        if kind == "HEARTBEAT":
            return kind if self._heartbeat(message) else ""
        if self.system_id is None or source != self.system_id:
            return ""
        handler = _HANDLERS.get(kind)
        if handler is None:
            return kind
        return kind if handler(self, message) is not False else ""

    def _heartbeat(self, m: Any) -> bool:
        if m.autopilot == MAV_AUTOPILOT_INVALID or m.type == MAV_TYPE_GCS:
            return False
        source, component = m.get_srcSystem(), m.get_srcComponent()
        if self.system_id is not None and source != self.system_id:
            return False
        if self.component_id is not None and component != self.component_id:
            return False
        self.system_id, self.component_id = source, component
        self.autopilot = int(m.autopilot)
        self.custom_mode = int(m.custom_mode)
        self.armed = bool(m.base_mode & MAV_MODE_FLAG_SAFETY_ARMED)
        self.heartbeats += 1
        return True

    def _local_position(self, m: Any) -> None:
        self.position_ned = (float(m.x), float(m.y), float(m.z))
        self.velocity_ned = (float(m.vx), float(m.vy), float(m.vz))
        self.position_time_ms = int(m.time_boot_ms)
        self.positions += 1

    def _attitude(self, m: Any) -> None:
        self.attitude_ned = (float(m.roll), float(m.pitch), float(m.yaw))
        self.attitude_time_ms = int(m.time_boot_ms)

    def _battery_status(self, m: Any) -> None:
        """BATTERY_STATUS: charge left, the pack voltage (the cells sent, summed: ArduPilot puts
        the whole pack in the first, PX4 one cell in each), the autopilot's time left."""
        if m.battery_remaining >= 0:
            self.battery_fraction = m.battery_remaining / 100.0
            self._battery_from_status = True
        cells_mv = [int(v) for v in m.voltages if int(v) not in (0, UNKNOWN_MV)]
        if cells_mv:
            self.battery_voltage_v = sum(cells_mv) / 1000.0
        time_remaining_s = int(getattr(m, "time_remaining", 0) or 0)
        self.battery_minutes_left = time_remaining_s / 60.0 if time_remaining_s > 0 else None

    def _sys_status(self, m: Any) -> None:
        self.prearm_good = bool(m.onboard_control_sensors_health & MAV_SYS_STATUS_PREARM_CHECK)
        self.prearm_mode = self.custom_mode
        if self.prearm_good:  # an explanation said since belongs to a new failure
            self.prearm_text = None
        if m.battery_remaining >= 0 and not self._battery_from_status:
            self.battery_fraction = m.battery_remaining / 100.0
        if m.voltage_battery not in (0, UNKNOWN_MV) and not self._battery_from_status:
            self.battery_voltage_v = m.voltage_battery / 1000.0

    def _estimator_status(self, m: Any) -> None:
        self.estimator_flags = int(m.flags)

    def _extended_sys_state(self, m: Any) -> None:
        self.landed_state = int(m.landed_state)

    def _statustext(self, m: Any) -> bool:
        text = m.text.decode(errors="replace") if isinstance(m.text, bytes) else str(m.text)
        whole = self._text_joiner.add(
            int(m.severity),
            text.split("\x00", 1)[0],
            int(getattr(m, "id", 0)),  # MAVLink 1 has neither field: one chunk
            int(getattr(m, "chunk_seq", 0)),
            self._clock(),
            zero_chunks=self.flavor is PX4,
        )
        self._keep_texts(whole)
        return bool(whole)

    def _keep_texts(self, chunks_joined: list[tuple[int, str]]) -> None:
        texts = [(severity, text.strip()) for severity, text in chunks_joined]
        # PX4 ends the texts it also sends as events with a tab (Commander.cpp): "Arming denied:
        # Resolve system health failures first\t" reached the operator's refusal message.
        self.texts.extend(texts)
        self.recent_texts.extend(texts)
        self.to_tell.extend(texts)
        for _, said in texts:
            if said.startswith(PREARM_EXPLANATIONS) or (
                said.startswith(PREARM_DENIAL) and self.prearm_text is None
            ):
                self.prearm_text = said

    def _command_ack(self, m: Any) -> bool:
        if getattr(m, "target_system", 0) not in (0, self.own_system_id):
            return False
        self.acks.append((int(m.command), int(m.result)))
        return True

    def _position_target(self, m: Any) -> None:
        self.target_stamp_ms = int(m.time_boot_ms)
        self.target_stamps += 1


MAV_SYS_STATUS_PREARM_CHECK = 0x10000000
"""SYS_STATUS sensor bit of the pre-arm checks (PX4 sets it in health only, ArduPilot in all)."""
PREARM_EXPLANATIONS = ("PreArm:", "Preflight Fail:", "Geofence:")
"""How a STATUSTEXT naming a failing pre-arm check begins: ArduPilot's (said when the failure
begins or changes, every 30 s while it lasts, and on MAV_CMD_RUN_PREARM_CHECKS), PX4's (said
when its health checks change, and on that command; its geofence's checks begin "Geofence:",
``geofenceCheck.cpp``)."""
PREARM_DENIAL = "Arming denied:"
"""PX4's refusal of an ARM, at times naming no check ("Resolve system health failures first"):
an explanation only until a better one comes."""
PREARM_UNSAID = "pre-arm checks failing"
"""The explanation while SYS_STATUS says the checks fail and the autopilot has not said why."""
MAV_LANDED_STATE_ON_GROUND = 1
"""EXTENDED_SYS_STATE ``landed_state``: on the ground."""
PX4_OFFBOARD_ON_GROUND = "in OFFBOARD on the ground, its pre-arm checks unknown: going to Hold"
"""The explanation while PX4 sits disarmed in OFFBOARD (see :attr:`LinkState.preflight`)."""

_HANDLERS = {
    "LOCAL_POSITION_NED": LinkState._local_position,
    "ATTITUDE": LinkState._attitude,
    "BATTERY_STATUS": LinkState._battery_status,
    "SYS_STATUS": LinkState._sys_status,
    "EXTENDED_SYS_STATE": LinkState._extended_sys_state,
    "ESTIMATOR_STATUS": LinkState._estimator_status,
    "EKF_STATUS_REPORT": LinkState._estimator_status,
    "STATUSTEXT": LinkState._statustext,
    "COMMAND_ACK": LinkState._command_ack,
    "POSITION_TARGET_LOCAL_NED": LinkState._position_target,
}
