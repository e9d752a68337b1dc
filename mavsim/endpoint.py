"""One simulated vehicle on the wire: a UDP MAVLink endpoint in front of an :class:`Autopilot`.

The endpoint binds ``host:port`` and answers every peer that sent it a packet in the last
``PEER_TIMEOUT_S`` (a companion computer, a pilot's ground station). Bytes are MAVLink 2 with the
``ardupilotmega`` dialect; the vehicle's system id is ``config.system_id``, component 1. It speaks
the parameter protocol (PARAM_SET / PARAM_REQUEST_READ / PARAM_REQUEST_LIST -> PARAM_VALUE) for
the parameters of :mod:`mavsim.params`; as PX4 does, a PX4 vehicle sends STATUSTEXT only to peers
whose ground-station heartbeat (MAV_TYPE_GCS) it heard within ``GCS_HEARTBEAT_TIMEOUT_S``.

Deviation from ArduPilot, on purpose: POSITION_TARGET_LOCAL_NED carries the ``time_boot_ms`` of the
setpoint being tracked (the sender's stamp), so a companion computer can measure the latency from
its setpoint to the vehicle's control loop (benchmarks/bench_mavlink.py).
"""

from __future__ import annotations

import math
import socket
import time
from collections import deque
from collections.abc import Callable

from pymavlink.dialects.v20 import ardupilotmega as mavlink

from mavsim.autopilot import Autopilot
from mavsim.autopilot_core import Result
from mavsim.config import VehicleConfig
from mavsim.errors import MavsimError
from mavsim.estimator import DEFAULT_INTERVAL_S as ESTIMATOR_INTERVAL_S
from mavsim.estimator import estimator_status
from mavsim.frames import attitude_enu_to_ned, enu_to_ned
from mavsim.mocap import odometry_is_pose
from mavsim.modes import CopterMode, from_px4, px4_custom_mode
from mavsim.params import ParamTable
from mavsim.px4 import Px4Autopilot
from mavsim.wire import (
    Pose,
    Stop,
    decode_attitude_target,
    decode_position_target,
    px4_view,
)

PEER_TIMEOUT_S = 10.0
"""A peer that sent nothing for this long (wall time) no longer receives telemetry."""
FORCE_DISARM_MAGIC = 21196.0
"""MAV_CMD_COMPONENT_ARM_DISARM param2 that forces disarming in the air."""
GCS_HEARTBEAT_TIMEOUT_S = 2.5
"""PX4 counts a link as having a ground station for this long after its heartbeat (vehicle time)."""


PREARM_CHECK = 0x10000000
"""SYS_STATUS sensor bit of the pre-arm checks (MAV_SYS_STATUS_PREARM_CHECK)."""


class VehicleEndpoint:
    """A UDP socket, a MAVLink codec and the autopilot behind them."""

    def __init__(self, config: VehicleConfig, *, wall_clock: Callable[[], float] = time.monotonic):
        self.config = config
        self.px4 = config.autopilot == "px4"
        self.autopilot = Px4Autopilot(config) if self.px4 else Autopilot(config)
        self._wall_clock = wall_clock
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self.sock.bind((config.host, config.port))
        except OSError as exc:
            self.sock.close()
            raise MavsimError(
                f"{config.vehicle_id}: cannot listen on udp {config.host}:{config.port}: {exc}"
            ) from exc
        self.sock.setblocking(False)
        self.port = int(self.sock.getsockname()[1])
        self._mav = mavlink.MAVLink(None, srcSystem=config.system_id, srcComponent=1)
        self._parser = mavlink.MAVLink(None)
        self._parser.robust_parsing = True
        self._peers: dict[tuple[str, int], float] = {}
        self._gcs_heard_s: dict[tuple[str, int], float] = {}
        """Vehicle time of each peer's last MAV_TYPE_GCS heartbeat."""
        telemetry_s = 1.0 / config.telemetry_rate_hz
        self.intervals_s: dict[int, float] = {
            mavlink.MAVLINK_MSG_ID_HEARTBEAT: 1.0,
            mavlink.MAVLINK_MSG_ID_SYS_STATUS: 1.0,
            mavlink.MAVLINK_MSG_ID_BATTERY_STATUS: 1.0,
            mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE: 1.0,
            mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED: telemetry_s,
            mavlink.MAVLINK_MSG_ID_ATTITUDE: telemetry_s,
            mavlink.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED: telemetry_s,
        }
        if self.px4:  # ArduPilot reports its EKF in EKF_STATUS_REPORT, not simulated here
            self.intervals_s[mavlink.MAVLINK_MSG_ID_ESTIMATOR_STATUS] = ESTIMATOR_INTERVAL_S
        self._defaults_s = dict(self.intervals_s)
        self._next_due_s: dict[int, float] = dict.fromkeys(self.intervals_s, 0.0)
        self.next_step_s = self.autopilot.airframe.dt_s
        self.bytes_in = 0
        self.bytes_out = 0
        self.received_stamp_age_ms: deque[float] = deque(maxlen=100_000)
        """For each setpoint received: this machine's monotonic clock in [ms] minus its
        ``time_boot_ms`` (a latency when the sender stamps with the same clock, as
        benchmarks/bench_mavlink.py does)."""
        self.applied_stamp_age_ms: deque[float] = deque(maxlen=100_000)
        """The same when the control loop takes the setpoint up (its next step)."""
        self._fresh_stamp_ms: int | None = None

    @property
    def url(self) -> str:
        """How a companion computer reaches this vehicle: ``udp:HOST:PORT``."""
        return f"udp:{self.config.host}:{self.port}"

    def fileno(self) -> int:
        return self.sock.fileno()

    def close(self) -> None:
        self.sock.close()

    # --- input -----------------------------------------------------------------------------------
    def receive(self, now_s: float) -> None:
        """Read every datagram waiting on the socket and act on its messages at ``now_s``."""
        while True:
            try:
                data, address = self.sock.recvfrom(65535)
            except (BlockingIOError, InterruptedError):
                break
            except ConnectionError:
                continue
            self.bytes_in += len(data)
            self._peers[address] = self._wall_clock()
            for message in self._parser.parse_buffer(data) or ():
                if message.get_type() == "HEARTBEAT" and message.type == mavlink.MAV_TYPE_GCS:
                    self._gcs_heard_s[address] = self.autopilot.now_s
                if message.get_type() != "BAD_DATA":
                    self.handle(message)
        self._flush_texts()

    def _for_me(self, message: mavlink.MAVLink_message) -> bool:
        return getattr(message, "target_system", 0) in (0, self.config.system_id)

    def handle(self, message: mavlink.MAVLink_message) -> None:
        """Act on one decoded message (time is the autopilot's current time)."""
        kind = message.get_type()
        if kind in ("HEARTBEAT", "BAD_DATA") or not self._for_me(message):
            return
        ap = self.autopilot
        if kind == "COMMAND_LONG":
            result = self._command(message)
            self._ack(message.command, result, message)
        elif kind == "SET_MODE":
            ok = message.base_mode & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
            custom = int(message.custom_mode)
            main, sub = (custom >> 16) & 0xFF, (custom >> 24) & 0xFF
            result = self._set_mode(custom, main, sub) if ok else Result.UNSUPPORTED
            self._ack(mavlink.MAVLINK_MSG_ID_SET_MODE, result, message)
        elif kind == "SET_POSITION_TARGET_LOCAL_NED":
            self._position_setpoint(message)
        elif kind == "SET_ATTITUDE_TARGET":
            self._attitude_setpoint(message)
        elif kind in ("PARAM_SET", "PARAM_REQUEST_READ", "PARAM_REQUEST_LIST"):
            self._param(kind, message)
        elif kind in ("VISION_POSITION_ESTIMATE", "ATT_POS_MOCAP"):
            ap.mocap_pose()
        elif kind == "ODOMETRY":
            xyz = (message.x, message.y, message.z)
            if odometry_is_pose(ap.flavor, message.frame_id, message.child_frame_id,
                                message.estimator_type, xyz):  # fmt: skip
                ap.mocap_pose()
        elif kind == "SET_GPS_GLOBAL_ORIGIN":  # both autopilots answer with the origin taken
            ap.ekf_origin_lla = (message.latitude * 1e-7, message.longitude * 1e-7,
                                 message.altitude * 1e-3)  # fmt: skip
            self.send(self._mav.gps_global_origin_encode(
                message.latitude, message.longitude, message.altitude))  # fmt: skip

    def _position_setpoint(self, message: mavlink.MAVLink_message) -> None:
        ap = self.autopilot
        if ap.mode != CopterMode.GUIDED and not self.px4:
            return  # ArduCopter ignores it outside GUIDED; PX4 takes it as proof of life
        pose = Pose(self.config.home_m_enu, ap.airframe.position_m_enu, ap.airframe.attitude_rad[2])
        decoded = px4_view(message, pose) if self.px4 else decode_position_target(message, pose)
        stamp = int(message.time_boot_ms)
        if isinstance(decoded, Stop):
            ap.stop_here()
        elif decoded is not None and ap.guided_setpoint(decoded, stamp):
            self._setpoint_arrived(stamp)

    def _attitude_setpoint(self, message: mavlink.MAVLink_message) -> None:
        ap = self.autopilot
        if ap.mode != CopterMode.GUIDED and not self.px4:
            return
        decoded = decode_attitude_target(message)
        stamp = int(message.time_boot_ms)
        if isinstance(decoded, Stop):
            if not self.px4:
                ap.stop_here()
        elif ap.attitude_setpoint(decoded, stamp):
            self._setpoint_arrived(stamp)

    def _param(self, kind: str, message: mavlink.MAVLink_message) -> None:
        """The parameter protocol; an unknown name gets no answer (as on the autopilots)."""
        table: ParamTable = self.autopilot.params
        if kind == "PARAM_REQUEST_LIST":
            for name in table.names:
                self._param_value(name)
            return
        if kind == "PARAM_REQUEST_READ" and message.param_index >= 0:
            names = table.names
            if message.param_index < len(names):
                self._param_value(names[message.param_index])
            return
        name = _param_name(message.param_id)
        if name not in table:
            return
        if kind == "PARAM_SET":
            table.set_from_link(name, float(message.param_value))
        self._param_value(name)

    def _param_value(self, name: str) -> None:
        table = self.autopilot.params
        value, kind = table.encode(name)
        index = table.names.index(name)
        self.send(self._mav.param_value_encode(name.encode(), value, kind, len(table.names), index))

    def _setpoint_arrived(self, stamp_ms: int) -> None:
        self._fresh_stamp_ms = stamp_ms
        self.received_stamp_age_ms.append(_age_ms(stamp_ms))

    def _command(self, message: mavlink.MAVLink_message) -> Result:
        ap = self.autopilot
        command = message.command
        if command == mavlink.MAV_CMD_COMPONENT_ARM_DISARM:
            if message.param1 > 0.5:
                return ap.arm()
            return ap.disarm(force=abs(message.param2 - FORCE_DISARM_MAGIC) < 0.5)
        if command == mavlink.MAV_CMD_DO_SET_MODE:
            if not int(message.param1) & mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED:
                return Result.UNSUPPORTED
            return self._set_mode(int(message.param2), int(message.param2), int(message.param3))
        if command == mavlink.MAV_CMD_RUN_PREARM_CHECKS:
            return ap.run_prearm_checks()
        if command == mavlink.MAV_CMD_NAV_TAKEOFF:
            return ap.takeoff(float(message.param7))
        if command == mavlink.MAV_CMD_NAV_LAND:
            return ap.land()
        if command == mavlink.MAV_CMD_DO_FLIGHTTERMINATION:
            return ap.terminate() if message.param1 > 0.5 else Result.ACCEPTED
        if command == mavlink.MAV_CMD_SET_MESSAGE_INTERVAL:
            return self._set_interval(int(message.param1), float(message.param2))
        if command == mavlink.MAV_CMD_REQUEST_MESSAGE:
            return self._request(int(message.param1))
        if command == mavlink.MAV_CMD_DO_SET_HOME:
            return ap.set_home_here() if message.param1 > 0.5 else Result.UNSUPPORTED
        if command == mavlink.MAV_CMD_BATTERY_RESET:
            return ap.battery_reset(int(message.param1), float(message.param2))
        return Result.UNSUPPORTED

    def _set_mode(self, custom_mode: int, px4_main: int, px4_sub: int) -> Result:
        """ArduPilot: the custom mode number; PX4: its main and sub mode."""
        if not self.px4:
            return self.autopilot.set_mode(custom_mode)
        mode = from_px4(px4_main, px4_sub)
        return self.autopilot.set_mode(-1 if mode is None else int(mode))

    def _set_interval(self, message_id: int, interval_us: float) -> Result:
        if message_id not in self._defaults_s:
            return Result.UNSUPPORTED
        if interval_us < 0:
            self.intervals_s[message_id] = math.inf
        elif interval_us == 0:
            self.intervals_s[message_id] = self._defaults_s[message_id]
        else:
            self.intervals_s[message_id] = max(interval_us * 1e-6, 0.001)
        self._next_due_s[message_id] = self.autopilot.now_s
        return Result.ACCEPTED

    def _request(self, message_id: int) -> Result:
        if message_id not in self._defaults_s:
            return Result.UNSUPPORTED
        self._next_due_s[message_id] = self.autopilot.now_s
        return Result.ACCEPTED

    def _ack(self, command: int, result: Result, request: mavlink.MAVLink_message) -> None:
        self._flush_texts()
        self.send(
            self._mav.command_ack_encode(
                command, int(result), 0, 0, request.get_srcSystem(), request.get_srcComponent()
            )
        )

    # --- output ----------------------------------------------------------------------------------
    def send(
        self, message: mavlink.MAVLink_message, *, only: set[tuple[str, int]] | None = None
    ) -> None:
        """Pack once and send to every live peer (``only``: to those of them)."""
        data = message.pack(self._mav)
        self._mav.seq = (self._mav.seq + 1) % 256
        now = self._wall_clock()
        for address, seen in list(self._peers.items()):
            if now - seen > PEER_TIMEOUT_S:
                del self._peers[address]
                continue
            if only is not None and address not in only:
                continue
            try:
                self.sock.sendto(data, address)
                self.bytes_out += len(data)
            except OSError:
                del self._peers[address]

    def _flush_texts(self) -> None:
        texts, self.autopilot.texts = self.autopilot.texts, []
        for severity, text in texts:
            message = self._mav.statustext_encode(severity, text.encode())
            if self.px4:
                self.send(message, only=self._ground_stations())
            else:
                self.send(message)

    def _ground_stations(self) -> set[tuple[str, int]]:
        """Peers whose MAV_TYPE_GCS heartbeat was heard lately (PX4 texts go only there)."""
        now = self.autopilot.now_s
        return {a for a, t in self._gcs_heard_s.items() if now - t <= GCS_HEARTBEAT_TIMEOUT_S}

    def step(self) -> None:
        """One autopilot period at ``next_step_s``."""
        self.autopilot.step(self.next_step_s)
        self.next_step_s += self.autopilot.airframe.dt_s
        if self._fresh_stamp_ms is not None:
            self.applied_stamp_age_ms.append(_age_ms(self._fresh_stamp_ms))
            self._fresh_stamp_ms = None
        self._flush_texts()

    def emit(self, now_s: float) -> None:
        """Send every telemetry message whose interval elapsed."""
        if not self._peers:
            return
        for message_id, interval in self.intervals_s.items():
            if now_s < self._next_due_s[message_id] or math.isinf(interval):
                continue
            self._next_due_s[message_id] = max(self._next_due_s[message_id] + interval, now_s)
            message = self._telemetry(message_id, now_s)
            if message is not None:
                self.send(message)

    def _telemetry(self, message_id: int, now_s: float) -> mavlink.MAVLink_message | None:
        ap = self.autopilot
        t_ms = int(now_s * 1000) & 0xFFFFFFFF
        if message_id == mavlink.MAVLINK_MSG_ID_HEARTBEAT:
            return self._heartbeat()
        if message_id == mavlink.MAVLINK_MSG_ID_LOCAL_POSITION_NED:
            home = self.config.home_m_enu
            p = ap.airframe.position_m_enu
            x, y, z = enu_to_ned((p[0] - home[0], p[1] - home[1], p[2] - home[2]))
            vx, vy, vz = enu_to_ned(ap.airframe.velocity_mps_enu)
            return self._mav.local_position_ned_encode(t_ms, x, y, z, vx, vy, vz)
        if message_id == mavlink.MAVLINK_MSG_ID_ATTITUDE:
            roll, pitch, yaw = attitude_enu_to_ned(*ap.airframe.attitude_rad)
            rates = ap.airframe.attitude_rate_radps
            return self._mav.attitude_encode(t_ms, roll, pitch, yaw, rates[0], -rates[1], -rates[2])
        if message_id == mavlink.MAVLINK_MSG_ID_POSITION_TARGET_LOCAL_NED:
            return self._position_target()
        if message_id == mavlink.MAVLINK_MSG_ID_EXTENDED_SYS_STATE:
            return self._mav.extended_sys_state_encode(0, ap.landed_state)
        if message_id == mavlink.MAVLINK_MSG_ID_ESTIMATOR_STATUS:
            return estimator_status(self._mav, ap)
        return self._battery(message_id)

    def _heartbeat(self) -> mavlink.MAVLink_message:
        ap = self.autopilot
        base = mavlink.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED | mavlink.MAV_MODE_FLAG_STABILIZE_ENABLED
        if ap.mode == CopterMode.GUIDED:
            base |= mavlink.MAV_MODE_FLAG_GUIDED_ENABLED
        if ap.armed:
            base |= mavlink.MAV_MODE_FLAG_SAFETY_ARMED
        status = mavlink.MAV_STATE_ACTIVE if ap.armed else mavlink.MAV_STATE_STANDBY
        if self.px4:
            autopilot, custom = mavlink.MAV_AUTOPILOT_PX4, px4_custom_mode(ap.mode)
        else:
            autopilot, custom = mavlink.MAV_AUTOPILOT_ARDUPILOTMEGA, int(ap.mode)
        return self._mav.heartbeat_encode(
            mavlink.MAV_TYPE_QUADROTOR, autopilot, base, custom, status
        )

    def _position_target(self) -> mavlink.MAVLink_message | None:
        ap = self.autopilot
        if ap.mode != CopterMode.GUIDED or ap.submode != "track":
            return None
        home = self.config.home_m_enu
        t = ap.target
        p = t.position_m_enu
        x, y, z = enu_to_ned((p[0] - home[0], p[1] - home[1], p[2] - home[2]))
        vx, vy, vz = enu_to_ned(t.velocity_mps_enu)
        ax, ay, az = enu_to_ned(t.acceleration_mps2_enu)
        return self._mav.position_target_local_ned_encode(
            ap.setpoint_stamp_ms & 0xFFFFFFFF, mavlink.MAV_FRAME_LOCAL_NED, 0x0C00,
            x, y, z, vx, vy, vz, ax, ay, az, math.pi / 2 - t.yaw_rad, 0.0,
        )  # fmt: skip

    def _battery(self, message_id: int) -> mavlink.MAVLink_message | None:
        battery = self.autopilot.battery
        if message_id == mavlink.MAVLINK_MSG_ID_SYS_STATUS:
            sensors = PREARM_CHECK  # present and enabled; healthy while its checks pass
            healthy = sensors if self.autopilot.prearm_bit else 0
            return battery.sys_status(self._mav, sensors, healthy)
        if message_id == mavlink.MAVLINK_MSG_ID_BATTERY_STATUS:
            return battery.battery_status(self._mav, self.autopilot.flavor)
        return None


def _param_name(raw: object) -> str:
    text = raw.decode(errors="replace") if isinstance(raw, bytes) else str(raw)
    return text.rstrip("\x00")


def _age_ms(stamp_ms: int) -> float:
    """Monotonic clock minus a ``time_boot_ms`` stamp, in [ms] (modulo 2^32 ms)."""
    now_ms = int(time.monotonic() * 1000) & 0xFFFFFFFF
    return float((now_ms - stamp_ms) & 0xFFFFFFFF)
