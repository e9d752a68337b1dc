"""A minimal ground station for the conformance suite: pymavlink only, nothing of skyquill.

Single-threaded: :meth:`Gcs.pump` reads what the autopilot says for a while, sends our heartbeat
once a second and, while a setpoint stream is set (:attr:`Gcs.stream`), one setpoint per period.
Every duration is in the autopilot's own seconds (``clock``: the wall clock for SITL, the
simulator's time for mavsim run faster than real time).
Positions are the autopilot's LOCAL_NED (x north, y east, z down) in [m].
"""

from __future__ import annotations

import math
import struct
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pymavlink import mavutil
from pymavlink.dialects.v20 import ardupilotmega as mav

GCS_SYSTEM, GCS_COMPONENT = 255, 190
Stream = Callable[["Gcs"], None]
Vec3 = tuple[float, float, float]

ARDUPILOT_MODES = {"GUIDED": 4, "LOITER": 5, "LAND": 9, "BRAKE": 17}
PX4_MODES = {"GUIDED": (6, 0), "LOITER": (4, 3), "LAND": (4, 6), "POSCTL": (3, 0)}
"""PX4 (main, sub) of the same roles: OFFBOARD, AUTO.LOITER (Hold), AUTO.LAND; and POSCTL."""


@dataclass
class Seen:
    """The latest of what the autopilot said."""

    heartbeat: Any = None
    position: Any = None
    attitude: Any = None
    extended: Any = None
    texts: list[tuple[int, str]] = field(default_factory=list)
    acks: list[tuple[int, int]] = field(default_factory=list)
    params: dict[str, tuple[float, int]] = field(default_factory=dict)


class Gcs:
    """One link to the autopilot under test."""

    def __init__(
        self,
        url: str,
        system_id: int,
        kind: str,
        *,
        clock: Callable[[], float] = time.monotonic,
        mav_type: int = mav.MAV_TYPE_GCS,
    ):
        self.kind = kind
        self.clock = clock
        """The autopilot's time in [s]: what every duration here is counted in."""
        self.system_id = system_id
        self.component_id = 1
        self.mav_type = mav_type
        """Our HEARTBEAT type (MAV_TYPE_GCS; a test may pose as an onboard controller)."""
        self.conn = mavutil.mavlink_connection(
            url, source_system=GCS_SYSTEM, source_component=GCS_COMPONENT, dialect="ardupilotmega"
        )
        self.seen = Seen()
        self.stream: Stream | None = None
        self.stream_period_s = 0.05
        self.silent = False
        """True: send nothing at all (a lost link)."""
        self.log: list[tuple[float, float, float, float, float]] | None = None
        """When a list: every LOCAL_POSITION_NED as (``clock`` time [s], x, y, z, vx)."""
        self._last_heartbeat = -math.inf
        self._last_setpoint = -math.inf

    def close(self) -> None:
        self.conn.close()

    # --- the loop --------------------------------------------------------------------------------
    def pump(self, seconds: float, until: Callable[[Seen], bool] | None = None) -> bool:
        """Listen (and send heartbeats and the stream) for ``seconds`` or until ``until``."""
        end = self.clock() + seconds
        while self.clock() < end:
            now = self.clock()
            if not self.silent and now - self._last_heartbeat >= 1.0:
                self._last_heartbeat = now
                self.conn.mav.heartbeat_send(self.mav_type, mav.MAV_AUTOPILOT_INVALID, 0, 0, 4)
            if (
                not self.silent
                and self.stream
                and now - self._last_setpoint >= self.stream_period_s
            ):
                self._last_setpoint = now
                self.stream(self)
            message = self.conn.recv_match(blocking=True, timeout=0.01)
            while message is not None:
                self._absorb(message)
                message = self.conn.recv_match(blocking=False)
            if until is not None and until(self.seen):
                return True
        return until is None

    def _absorb(self, m: Any) -> None:
        if m.get_srcSystem() != self.system_id:
            return
        kind, seen = m.get_type(), self.seen
        if kind == "HEARTBEAT" and m.get_srcComponent() == self.component_id:
            seen.heartbeat = m
        elif kind == "LOCAL_POSITION_NED":
            seen.position = m
            if self.log is not None:
                self.log.append((self.clock(), float(m.x), float(m.y), float(m.z), float(m.vx)))
        elif kind == "ATTITUDE":
            seen.attitude = m
        elif kind == "EXTENDED_SYS_STATE":
            seen.extended = m
        elif kind == "STATUSTEXT":
            seen.texts.append((int(m.severity), str(m.text)))
        elif kind == "COMMAND_ACK" and getattr(m, "target_system", 0) in (0, GCS_SYSTEM):
            seen.acks.append((int(m.command), int(m.result)))
        elif kind == "PARAM_VALUE":
            seen.params[str(m.param_id)] = (float(m.param_value), int(m.param_type))

    def connect(self) -> None:
        """Wait for its heartbeat, ask for position, attitude and landed state at 20 Hz."""
        assert self.pump(30.0, lambda s: s.heartbeat is not None), "no heartbeat from the vehicle"
        for message_id, rate_hz in ((32, 20.0), (30, 20.0), (245, 5.0)):
            self.command(mav.MAV_CMD_SET_MESSAGE_INTERVAL, message_id, 1e6 / rate_hz)
        assert self.pump(5.0, lambda s: s.position is not None), "no LOCAL_POSITION_NED"

    # --- commands --------------------------------------------------------------------------------
    def command(self, command: int, *params: float, timeout_s: float = 3.0) -> int:
        """COMMAND_LONG, retried once a second; the MAV_RESULT of its ACK."""
        padded = [*params, *([0.0] * (7 - len(params)))]
        start = len(self.seen.acks)
        for confirmation in range(round(timeout_s)):
            self.conn.mav.command_long_send(self.system_id, self.component_id, command,
                                            confirmation, *padded)  # fmt: skip
            if self.pump(1.0, lambda s: any(c == command for c, _ in s.acks[start:])):
                return next(r for c, r in self.seen.acks[start:] if c == command)
        raise AssertionError(f"no COMMAND_ACK for command {command}")

    def set_mode(self, role: str) -> int:
        """Switch to the mode of ``role`` (GUIDED means OFFBOARD on PX4)."""
        if self.kind == "px4":
            main, sub = PX4_MODES[role]
            return self.command(mav.MAV_CMD_DO_SET_MODE, 1, main, sub)
        return self.command(mav.MAV_CMD_DO_SET_MODE, 1, ARDUPILOT_MODES[role])

    def in_mode(self, role: str) -> bool:
        hb = self.seen.heartbeat
        if hb is None:
            return False
        if self.kind == "px4":
            main, sub = PX4_MODES[role]
            return bool((hb.custom_mode >> 16) & 0xFF == main and (main != 4 or
                        (hb.custom_mode >> 24) & 0xFF == sub))  # fmt: skip
        return int(hb.custom_mode) == ARDUPILOT_MODES[role]

    def arm(self, *, retry_s: float = 0.0) -> int:
        """Arm; with ``retry_s`` keep trying while the vehicle is not ready (SITL's EKF)."""
        end = self.clock() + retry_s
        while True:
            result = self.command(mav.MAV_CMD_COMPONENT_ARM_DISARM, 1)
            if result == mav.MAV_RESULT_ACCEPTED or self.clock() >= end:
                return result
            self.pump(1.0)

    @property
    def armed(self) -> bool:
        hb = self.seen.heartbeat
        return hb is not None and bool(hb.base_mode & mav.MAV_MODE_FLAG_SAFETY_ARMED)

    # --- parameters ------------------------------------------------------------------------------
    def set_param(self, name: str, value: float, param_type: int) -> float | None:
        """PARAM_SET; the value of the PARAM_VALUE answer (None: no answer within 2 s). PX4
        carries integers bytewise in the float field (both ways)."""
        bytewise = self.kind == "px4" and param_type == mav.MAV_PARAM_TYPE_INT32
        raw = struct.unpack("<f", struct.pack("<i", int(value)))[0] if bytewise else value
        self.seen.params.pop(name, None)
        self.conn.mav.param_set_send(self.system_id, self.component_id, name.encode(), raw,
                                     param_type)  # fmt: skip
        if not self.pump(2.0, lambda s: name in s.params):
            return None
        answer = self.seen.params[name][0]
        return float(struct.unpack("<i", struct.pack("<f", answer))[0]) if bytewise else answer

    # --- setpoints -------------------------------------------------------------------------------
    def send_target(self, mask: int, p: Vec3 = (0.0, 0.0, 0.0), v: Vec3 = (0.0, 0.0, 0.0),
                    yaw: float = 0.0) -> None:  # fmt: skip
        """SET_POSITION_TARGET_LOCAL_NED with ``mask``."""
        stamp = int(time.monotonic() * 1000) & 0xFFFFFFFF  # this machine's, as a companion's
        self.conn.mav.set_position_target_local_ned_send(
            stamp, self.system_id, self.component_id, mav.MAV_FRAME_LOCAL_NED, mask,
            *p, *v, 0.0, 0.0, 0.0, yaw, 0.0,
        )  # fmt: skip

    def here(self) -> tuple[float, float, float]:
        p = self.seen.position
        return (float(p.x), float(p.y), float(p.z))

    def speed_mps(self) -> float:
        p = self.seen.position
        return math.sqrt(p.vx * p.vx + p.vy * p.vy + p.vz * p.vz)

    def yaw_rad(self) -> float:
        return float(self.seen.attitude.yaw)

    def airborne(self, height_m: float = 1.0, *, within_s: float = 30.0) -> None:
        """Take off to ``height_m`` above where it stands and hold there (GUIDED / OFFBOARD)."""
        x, y, z = self.here()
        top = (x, y, z - height_m)
        if self.kind == "px4":
            hold = (x, y, z)
            self.stream = lambda g: g.send_target(0x0DF8, hold)
            self.pump(1.2)
            assert self.set_mode("GUIDED") == mav.MAV_RESULT_ACCEPTED, self.seen.texts[-3:]
            assert self.arm(retry_s=30.0) == mav.MAV_RESULT_ACCEPTED, self.seen.texts[-3:]
            self.stream = lambda g: g.send_target(0x0DF8, top)
        else:
            assert self.set_mode("GUIDED") == mav.MAV_RESULT_ACCEPTED, self.seen.texts[-3:]
            assert self.arm(retry_s=30.0) == mav.MAV_RESULT_ACCEPTED, self.seen.texts[-3:]
            result = self.command(mav.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, height_m)
            assert result == mav.MAV_RESULT_ACCEPTED, self.seen.texts[-3:]
        reached = self.pump(within_s, lambda s: abs(float(s.position.z) - top[2]) < 0.15
                            and self.speed_mps() < 0.1)  # fmt: skip
        assert reached, f"not at {height_m} m within {within_s} s: {self.here()}"
