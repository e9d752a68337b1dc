"""When a fresh SITL instance is ready for the agent, judged on start.py's own link to it.

start.py never opens the agent's link (:attr:`Instance.url`): the agent may hold it already
(PX4: ``skyquill up`` started first listens there) or connect any moment (ArduCopter: SERIAL0
takes one client). It asks on :attr:`Instance.probe_url` instead and waits for:

- **a vehicle without mocap**: a 3-D GPS fix, a local position and the pre-arm checks passing
  (SYS_STATUS's pre-arm bit): it could arm now;
- **a vehicle on mocap**: the agent forwards the mocap only after it has connected, so the
  pre-arm checks cannot pass before (ArduCopter: "PreArm: VisOdom: not healthy") and neither
  can a position on the mocap. Ready is then: booted and the simulator running (PX4: a 3-D fix
  of the simulated GPS, the sensors simulated and read; ArduCopter boots without a GPS on mocap,
  its running EKF shows the same), the boot parameters loaded (each of
  :func:`boot_params` read back with its value: the instance will fuse what the agent sends),
  and the EKF running with its attitude aligned (EKF_STATUS_REPORT on ArduCopter,
  ESTIMATOR_STATUS on PX4, flag ESTIMATOR_ATTITUDE): what is left is the position, which only
  the mocap gives.

Free of project imports (start.py imports it by path).
"""

from __future__ import annotations

import math
import subprocess
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from instances import Instance, SitlError, boot_params

STOP_REQUESTED = threading.Event()
"""Set by start.py's handler of a stop signal, which also raises KeyboardInterrupt: pymavlink
runs bare ``except:`` clauses (``mavutil`` importing ``curses``, its wire-version sniffing) that
swallow it when the signal lands inside one, and start.py then waited for its instances until
the ready timeout (a test's ``kill``, about one run in six). The waits here look at this too."""
MAV_SYS_STATUS_PREARM_CHECK = 0x10000000
ESTIMATOR_ATTITUDE = 0x1
EKF_MESSAGE_ID = {"ardupilot": 193, "px4": 230}
"""EKF_STATUS_REPORT (ArduPilot) and ESTIMATOR_STATUS (PX4): both carry the EKF's flags."""
EKF_MESSAGE = {"ardupilot": "EKF_STATUS_REPORT", "px4": "ESTIMATOR_STATUS"}
STREAMED_IDS = (1, 24, 32)
"""SYS_STATUS, GPS_RAW_INT, LOCAL_POSITION_NED: asked for at 2 Hz on the probe link."""
GCS_SYSTEM_ID, GCS_COMPONENT_ID = 255, 191
"""The probe's MAVLink address (a ground station's; the agent uses its own)."""
PARAM_TOLERANCE = 1e-6


@dataclass
class Readiness:
    """What one instance has shown on the probe link (pure: fed messages, asked what is left)."""

    kind: str
    mocap: bool
    params_expected: dict[str, float]
    gps_fix: bool = False
    local_position: bool = False
    prearm: bool = False
    ekf_attitude: bool = False
    params_seen: dict[str, float] = field(default_factory=dict)
    texts: list[str] = field(default_factory=list)
    waited_s: float = 0.0
    """From the start of :func:`wait_ready` until ready, in [s]."""

    def update(self, msg: Any) -> None:
        """Take one message from the instance (its system id already checked)."""
        kind = msg.get_type()
        if kind == "GPS_RAW_INT":
            self.gps_fix = msg.fix_type >= 3
        elif kind == "LOCAL_POSITION_NED":
            self.local_position = True
        elif kind == "SYS_STATUS":  # PX4 sets the bit in health only, ArduPilot in both
            self.prearm = bool(msg.onboard_control_sensors_health & MAV_SYS_STATUS_PREARM_CHECK)
        elif kind == EKF_MESSAGE[self.kind]:
            self.ekf_attitude = bool(msg.flags & ESTIMATOR_ATTITUDE)
        elif kind == "PARAM_VALUE":
            name = str(msg.param_id).rstrip("\0")
            if name in self.params_expected:
                self.params_seen[name] = float(msg.param_value)
        elif kind == "STATUSTEXT":
            self.texts.append(str(msg.text))

    def params_missing(self) -> list[str]:
        """Boot parameters not yet read back with their value."""
        return [
            name
            for name, value in self.params_expected.items()
            if not math.isclose(self.params_seen.get(name, math.nan), value,
                                abs_tol=PARAM_TOLERANCE)
        ]  # fmt: skip

    def conditions(self) -> dict[str, bool]:
        """Each condition of ready (module docstring) and whether it holds."""
        if not self.mocap:
            return {"gps fix": self.gps_fix, "local position": self.local_position,
                    "pre-arm good": self.prearm}  # fmt: skip
        loaded = f"boot parameters {', '.join(self.params_expected)}"
        running = {loaded: not self.params_missing(),
                   f"EKF attitude ({EKF_MESSAGE[self.kind]})": self.ekf_attitude}  # fmt: skip
        if self.kind == "ardupilot":  # booted without a GPS (instances.MOCAP_BOOT_PARAMS)
            return running
        return {"gps fix": self.gps_fix} | running

    def ready(self) -> bool:
        return all(self.conditions().values())

    def summary(self) -> str:
        """What was waited for, and for a vehicle on mocap what it still waits for."""
        text = ", ".join(name for name in self.conditions())
        if self.mocap:
            prearm = [t for t in self.texts if "PreArm" in t or "Preflight" in t]
            text += "; position and pre-arm wait for the agent's mocap"
            if prearm:
                text += f" (last: {prearm[-1]!r})"
        return text


def wait_ready(inst: Instance, proc: subprocess.Popen[bytes], timeout_s: float) -> Readiness:
    """Wait until ``inst`` is ready (module docstring) on its probe link; returns what was seen.
    SitlError (with the conditions and the last autopilot texts) on timeout or
    when the process exits."""
    from pymavlink import mavutil

    t0 = time.monotonic()
    conn = _connect(mavutil, inst.probe_url, proc, t0 + timeout_s)
    state = Readiness(inst.kind, inst.mocap, boot_params(inst))
    try:
        _poll(conn, inst, state, proc, t0 + timeout_s)
    finally:
        conn.close()
    state.waited_s = time.monotonic() - t0
    return state


def _connect(mavutil: Any, url: str, proc: subprocess.Popen[bytes], deadline: float) -> Any:
    while True:  # ArduCopter's TCP port opens a moment after the process starts
        _stop_if_requested()
        if proc.poll() is not None:
            raise SitlError(f"SITL exited with status {proc.returncode} before {url} opened")
        try:
            return mavutil.mavlink_connection(url, source_system=GCS_SYSTEM_ID,
                                              source_component=GCS_COMPONENT_ID,
                                              autoreconnect=False)  # fmt: skip
        except (ConnectionError, OSError):
            if time.monotonic() > deadline:
                raise SitlError(f"{url} did not open") from None
            time.sleep(0.5)


def _poll(
    conn: Any, inst: Instance, state: Readiness, proc: subprocess.Popen[bytes], deadline: float
) -> None:
    next_ask = 0.0
    while not state.ready():
        _stop_if_requested()
        now = time.monotonic()
        if proc.poll() is not None:
            raise SitlError(
                f"SITL exited with status {proc.returncode}; last texts: {state.texts[-5:]}"
            )
        if now > deadline:
            raise SitlError(f"{inst.kind} instance {inst.index} not ready: {state.conditions()}; "
                            f"last texts: {state.texts[-5:]}")  # fmt: skip
        if now >= next_ask:
            next_ask = now + 1.0
            _ask(conn, inst, state)
        msg = conn.recv_match(blocking=True, timeout=0.2)
        if msg is not None and msg.get_srcSystem() == inst.system_id:
            state.update(msg)


def _stop_if_requested() -> None:
    if STOP_REQUESTED.is_set():
        raise KeyboardInterrupt


def _ask(conn: Any, inst: Instance, state: Readiness) -> None:
    """Once a second: a GCS heartbeat, the streams wanted, the boot parameters not yet seen."""
    conn.mav.heartbeat_send(6, 8, 0, 0, 4)  # GCS, no autopilot, active
    for msg_id in (*STREAMED_IDS, EKF_MESSAGE_ID[inst.kind]):
        conn.mav.command_long_send(inst.system_id, 1, 511, 0, msg_id, 5e5, 0, 0, 0, 0, 0)
    for name in state.params_missing():
        conn.mav.param_request_read_send(inst.system_id, 1, name.encode(), -1)
