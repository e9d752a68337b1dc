"""Start real autopilot SITL instances (ArduCopter, PX4 SIH) for a show; stop them cleanly.

    .venv/bin/python scripts/sitl/start.py shows/sitl-ardupilot.yaml   # Ctrl-C stops them

One instance per ``backend: mavlink`` vehicle of the show. The vehicle's ``mavlink_url`` says
which autopilot and which instance it is:

- ArduCopter: ``tcp:127.0.0.1:PORT`` with PORT = 5760 + 10*I (SERIAL0 of instance I), system id
  ``mavlink_system_id`` (``--sysid``); binary from ``--arducopter`` or $SKYQUILL_ARDUCOPTER_SITL;
- PX4 SIH quadrotor: ``udpin:127.0.0.1:PORT`` with PORT = 14540 + I (PX4 ``-i I`` sends its
  offboard link there from 14580 + I); PX4 forces MAV_SYS_ID = I + 1, so that must be the
  vehicle's ``mavlink_system_id``; binary from ``--px4`` or $SKYQUILL_PX4_SITL.

A PX4 vehicle that forwards mocap flies a research airframe: SIH's armed IMU noise at its
disarmed level (``SIH_IMU_VIB`` 0, a parameter scripts/sitl/build.py adds to SIH;
``--px4-imu-vibration`` says otherwise). SIH's stock airframe vibrates too much for centimetre
writing (scripts/sitl/source_edits.py says what was measured).

Each instance starts at the geodetic point of the vehicle's ``home_m_enu`` (east/north metres from
a reference point), which is also its LOCAL_NED origin, and runs in its own directory under
``--run-dir`` (eeprom, logs, parameters; its console output in ``console.log``). ArduCopter starts
with its parameters wiped to Tools/autotest/default_params/copter.parm. Use binaries whose
listeners are bound to 127.0.0.1 (README, "Real autopilot SITL").

This file is also imported by path (tests/conformance/sitl_targets.py): keep it free of project
imports at module level.
"""

from __future__ import annotations

import argparse
import contextlib
import math
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

Kind = Literal["ardupilot", "px4"]
ENV_BINARY: dict[str, str] = {
    "ardupilot": "SKYQUILL_ARDUCOPTER_SITL",
    "px4": "SKYQUILL_PX4_SITL",
}
"""Environment variable naming each kind's SITL binary."""
REFERENCE_LLA = (-35.363261, 149.165230, 584.0)
"""Geodetic point (lat [deg], lon [deg], alt [m]) of the show frame's origin (ArduPilot's CMAC)."""
EARTH_RADIUS_M = 6_378_137.0
ARDUPILOT_BASE_PORT = 5760
MOCAP_PARM = "mocap.parm"
MOCAP_BOOT_PARAMS = (
    "VISO_TYPE 1\nEK3_SRC1_POSXY 6\nEK3_SRC1_POSZ 6\nEK3_SRC1_VELXY 0\nEK3_SRC1_VELZ 0\n"
)
"""ArduCopter parameters that fusing forwarded mocap needs from boot on: VISO_TYPE is read only at
boot; the EKF3 sources (ExternalNav; the agent sets them too, as in
``vehicle_agent/backends/mavlink_params.py``) because a SITL whose GPS gets its fix before the
agent has set them takes its EKF origin from the GPS, then never uses the mocap ("PreArm: Fence
enabled, need position estimate", "Check mag field"): 7 of 10 ArduCopter starts with mocap in
one day, where connecting and setting the parameters took up to 18 s instead of 6."""
PX4_MOCAP_BOOT_PARAMS = {"EKF2_ASP_DELAY": "0", "EKF2_DELAY_MAX": "20"}
"""The same for PX4, given as PX4_PARAM_* variables (vehicle_agent/backends/mavlink_params.py
sets and checks them at connect, and refuses a vehicle that would need a reboot)."""
PX4_OFFBOARD_REMOTE_PORT = 14540
PX4_VIBRATION_PARAM = "SIH_IMU_VIB"
"""SIH's armed IMU noise as a fraction of its own (added by scripts/sitl/source_edits.py)."""
RESEARCH_AIRFRAME_VIBRATION = 0.0
"""SIH_IMU_VIB of a vehicle on mocap: SIH's disarmed noise level (0.1 m/s^2, 0.01 rad/s)."""
MAV_SYS_STATUS_PREARM_CHECK = 0x10000000
READY_TIMEOUT_S = 180.0
"""Longest wait for a fresh instance to be ready to arm, in [s] (ArduCopter's EKF: ~40 s)."""


class SitlError(Exception):
    """A SITL instance could not be described, started or readied; the message says why."""


@dataclass(frozen=True)
class Instance:
    """One SITL process to run."""

    kind: Kind
    """Which autopilot."""
    index: int
    """Instance number I (ports offset by 10*I for ArduCopter, by I for PX4)."""
    system_id: int
    """MAVLink system id of the autopilot."""
    home_lla: tuple[float, float, float]
    """Start point: latitude [deg], longitude [deg], altitude [m] above mean sea level."""
    binary: Path
    """The arducopter or px4 executable."""
    run_dir: Path
    """Working directory of this instance (created)."""
    mocap: bool = False
    """The agent forwards motion capture: ArduCopter boots with VISO_TYPE 1 and ExternalNav as
    its EKF3 sources (``MOCAP_BOOT_PARAMS``; the agent sets and verifies them again at connect)."""
    imu_vibration: float | None = None
    """PX4 SIH: its armed IMU noise as a fraction of SIH's own (:data:`PX4_VIBRATION_PARAM`, needs
    a binary built by scripts/sitl/build.py); None leaves SIH's."""

    @property
    def url(self) -> str:
        """Where the agent reaches it (pymavlink and ``mavlink_url`` mean the same here)."""
        if self.kind == "ardupilot":
            return f"tcp:127.0.0.1:{ARDUPILOT_BASE_PORT + 10 * self.index}"
        return f"udpin:127.0.0.1:{PX4_OFFBOARD_REMOTE_PORT + self.index}"


def as_kind(text: str) -> Kind:
    """``text`` as a :data:`Kind`; SitlError naming the kinds otherwise."""
    if text == "ardupilot":
        return "ardupilot"
    if text == "px4":
        return "px4"
    raise SitlError(f"unknown autopilot {text!r}: expected ardupilot or px4")


def url_instance(url: str) -> tuple[Kind, int]:
    """(kind, instance index) of a SITL vehicle's ``mavlink_url``; SitlError if it is none."""
    scheme, _, rest = url.partition(":")
    port_text = rest.rpartition(":")[2]
    if not port_text.isdigit():
        raise SitlError(f"mavlink_url {url!r}: no port")
    port = int(port_text)
    if scheme == "tcp" and port >= ARDUPILOT_BASE_PORT and (port - ARDUPILOT_BASE_PORT) % 10 == 0:
        return "ardupilot", (port - ARDUPILOT_BASE_PORT) // 10
    if scheme == "udpin" and PX4_OFFBOARD_REMOTE_PORT <= port < PX4_OFFBOARD_REMOTE_PORT + 10:
        return "px4", port - PX4_OFFBOARD_REMOTE_PORT
    raise SitlError(
        f"mavlink_url {url!r} is no SITL instance: expected tcp:127.0.0.1:5760+10*I (ArduCopter) "
        "or udpin:127.0.0.1:14540+I with I < 10 (PX4)"
    )


def home_lla(home_m_enu: tuple[float, float, float]) -> tuple[float, float, float]:
    """Geodetic point of a show-frame position (flat earth around :data:`REFERENCE_LLA`)."""
    lat0, lon0, alt0 = REFERENCE_LLA
    east, north, up = home_m_enu
    lat = lat0 + math.degrees(north / EARTH_RADIUS_M)
    lon = lon0 + math.degrees(east / (EARTH_RADIUS_M * math.cos(math.radians(lat0))))
    return (lat, lon, alt0 + up)


def binary_for(kind: Kind, explicit: str | None = None) -> Path:
    """The executable of ``kind``: ``explicit`` or its environment variable; SitlError if none."""
    value = explicit or os.environ.get(ENV_BINARY[kind], "")
    if not value:
        raise SitlError(f"{ENV_BINARY[kind]} not set: path of the {kind} SITL binary")
    path = Path(value)
    if not (path.is_file() and os.access(path, os.X_OK)):
        raise SitlError(f"{ENV_BINARY[kind]}={value}: not an executable file")
    return path


def command(inst: Instance) -> tuple[list[str], dict[str, str]]:
    """argv and environment of ``inst`` (pure)."""
    lat, lon, alt = inst.home_lla
    env = dict(os.environ)
    if inst.kind == "ardupilot":
        defaults = _copter_defaults(inst.binary)
        argv = [
            str(inst.binary),
            "--model",
            "quad",
            "--speedup",
            "1",
            "-I",
            str(inst.index),
            "--sysid",
            str(inst.system_id),
            "--home",
            f"{lat:.7f},{lon:.7f},{alt:.2f},0",
            "--defaults",
            ",".join([str(defaults)] + ([str(inst.run_dir / MOCAP_PARM)] if inst.mocap else [])),
            "--wipe",
            "--serial0",
            "tcp:0",
        ]
        return argv, env
    etc = inst.binary.resolve().parents[1] / "etc"  # build/px4_sitl_default/bin/px4
    env.update(
        PX4_SIM_MODEL="sihsim_quadx",
        PX4_SIMULATOR="sihsim",
        PX4_HOME_LAT=f"{lat:.7f}",
        PX4_HOME_LON=f"{lon:.7f}",
        PX4_HOME_ALT=f"{alt:.2f}",
    )
    if inst.mocap:
        env.update({f"PX4_PARAM_{name}": value for name, value in PX4_MOCAP_BOOT_PARAMS.items()})
    if inst.imu_vibration is not None:
        env[f"PX4_PARAM_{PX4_VIBRATION_PARAM}"] = f"{inst.imu_vibration:g}"
    return [str(inst.binary), "-i", str(inst.index), "-d", str(etc)], env


def _copter_defaults(binary: Path) -> Path:
    """SRC/Tools/autotest/default_params/copter.parm of SRC/build/sitl/bin/arducopter."""
    parents = binary.resolve().parents
    if len(parents) < 4:
        raise SitlError(f"{binary}: expected SRC/build/sitl/bin/arducopter")
    return parents[3] / "Tools" / "autotest" / "default_params" / "copter.parm"


def check_instance(inst: Instance) -> None:
    """SitlError when ``inst`` cannot run as described."""
    if inst.kind == "px4" and inst.system_id != inst.index + 1:
        raise SitlError(
            f"PX4 instance {inst.index} always has MAV_SYS_ID {inst.index + 1}, not "
            f"{inst.system_id}: use udpin:127.0.0.1:{PX4_OFFBOARD_REMOTE_PORT + inst.system_id - 1}"
        )
    if inst.imu_vibration is not None:
        if inst.kind != "px4" or not 0.0 <= inst.imu_vibration <= 1.0:
            raise SitlError(f"IMU vibration {inst.imu_vibration}: PX4 SIH only, from 0 to 1")
        if not binary_has(inst.binary, PX4_VIBRATION_PARAM.encode()):
            raise SitlError(
                f"{inst.binary} has no {PX4_VIBRATION_PARAM}: build it with scripts/sitl/build.py "
                '(README, "Real autopilot SITL"), or --px4-imu-vibration stock for SIH\'s '
                "vibrating airframe (no centimetre writing)"
            )
    if inst.kind == "ardupilot":
        defaults = _copter_defaults(inst.binary)
        if not defaults.is_file():
            raise SitlError(f"{defaults}: ArduCopter defaults not found beside {inst.binary}")


def binary_has(binary: Path, name: bytes, chunk_bytes: int = 1 << 22) -> bool:
    """Whether ``name`` occurs in the file ``binary`` (a PX4 binary names its parameters)."""
    with open(binary, "rb") as f:
        tail = b""
        while chunk := f.read(chunk_bytes):
            if name in tail + chunk:
                return True
            tail = chunk[-len(name) :]
    return False


def start(inst: Instance) -> subprocess.Popen[bytes]:
    """Start ``inst`` in its own process group; its console goes to ``run_dir/console.log``."""
    check_instance(inst)
    argv, env = command(inst)
    inst.run_dir.mkdir(parents=True, exist_ok=True)
    if inst.mocap and inst.kind == "ardupilot":
        (inst.run_dir / MOCAP_PARM).write_text(MOCAP_BOOT_PARAMS)
    with open(inst.run_dir / "console.log", "wb") as console:
        return subprocess.Popen(
            argv,
            cwd=inst.run_dir,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=console,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )


def stop(proc: subprocess.Popen[bytes], timeout_s: float = 10.0) -> int:
    """SIGTERM then, after ``timeout_s``, SIGKILL to the process group ``proc`` leads (the
    instance and its children); returns its exit status."""
    if proc.poll() is None:
        _signal_group(proc, signal.SIGTERM)
        try:
            proc.wait(timeout=timeout_s)
        except subprocess.TimeoutExpired:
            _signal_group(proc, signal.SIGKILL)
            proc.wait(timeout=timeout_s)
    _signal_group(proc, signal.SIGKILL)  # children left behind by a leader that exited
    return int(proc.returncode)


def _signal_group(proc: subprocess.Popen[bytes], sig: int) -> None:
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, sig)


def wait_ready(inst: Instance, proc: subprocess.Popen[bytes], timeout_s: float) -> float:
    """Wait until ``inst`` could arm: a 3-D GPS fix, a local position and the pre-arm checks
    passing; returns the seconds waited. SitlError (with the last autopilot texts) on timeout or
    when the process exits."""
    from pymavlink import mavutil

    t0 = time.monotonic()
    conn = _connect(mavutil, inst.url, proc, t0 + timeout_s)
    try:
        return _poll_ready(conn, inst, proc, t0, timeout_s)
    finally:
        conn.close()


def _connect(mavutil: Any, url: str, proc: subprocess.Popen[bytes], deadline: float) -> Any:
    while True:  # ArduCopter's TCP port opens a moment after the process starts
        if proc.poll() is not None:
            raise SitlError(f"SITL exited with status {proc.returncode} before {url} opened")
        try:
            return mavutil.mavlink_connection(
                url, source_system=255, source_component=191, autoreconnect=False
            )
        except (ConnectionError, OSError):
            if time.monotonic() > deadline:
                raise SitlError(f"{url} did not open") from None
            time.sleep(0.5)


def _poll_ready(
    conn: Any, inst: Instance, proc: subprocess.Popen[bytes], t0: float, timeout_s: float
) -> float:
    fix = local = prearm = False
    texts: list[str] = []
    next_beat = 0.0
    while True:
        now = time.monotonic()
        if proc.poll() is not None:
            raise SitlError(f"SITL exited with status {proc.returncode}; last texts: {texts[-5:]}")
        if now - t0 > timeout_s:
            raise SitlError(
                f"{inst.kind} instance {inst.index} not ready after {timeout_s:.0f} s (gps fix "
                f"{fix}, local position {local}, pre-arm good {prearm}); last texts: {texts[-5:]}"
            )
        if now >= next_beat:
            next_beat = now + 1.0
            conn.mav.heartbeat_send(6, 8, 0, 0, 4)  # GCS, no autopilot, active
            for msg_id in (1, 24, 32):  # SYS_STATUS, GPS_RAW_INT, LOCAL_POSITION_NED: 2 Hz
                conn.mav.command_long_send(inst.system_id, 1, 511, 0, msg_id, 5e5, 0, 0, 0, 0, 0)
        msg = conn.recv_match(blocking=True, timeout=0.2)
        if msg is None or msg.get_srcSystem() != inst.system_id:
            continue
        kind = msg.get_type()
        if kind == "GPS_RAW_INT":
            fix = msg.fix_type >= 3
        elif kind == "LOCAL_POSITION_NED":
            local = True
        elif kind == "SYS_STATUS":  # PX4 sets the bit in health only, ArduPilot in both
            prearm = bool(msg.onboard_control_sensors_health & MAV_SYS_STATUS_PREARM_CHECK)
        elif kind == "STATUSTEXT":
            texts.append(str(msg.text))
        if fix and local and prearm:
            return time.monotonic() - t0


def show_instances(
    show_path: Path,
    run_dir: Path,
    binaries: dict[str, str | None],
    px4_imu_vibration: float | None = RESEARCH_AIRFRAME_VIBRATION,
) -> list[Any]:
    """(vehicle id, Instance) of every ``backend: mavlink`` vehicle of the show; PX4 vehicles on
    mocap get ``px4_imu_vibration`` (None: SIH's own)."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
    from showfile import load_show

    show = load_show(show_path)
    found = []
    for vehicle in show.vehicles:
        if vehicle.backend != "mavlink" or not vehicle.mavlink_url:
            continue
        kind, index = url_instance(vehicle.mavlink_url)
        if vehicle.mavlink_system_id is None:
            raise SitlError(f"{show_path}: vehicle {vehicle.id} needs mavlink_system_id")
        inst = Instance(
            kind,
            index,
            vehicle.mavlink_system_id,
            home_lla(vehicle.home_m_enu),
            binary_for(kind, binaries[kind]),
            run_dir / f"{kind}-{index}",
            mocap=vehicle.mavlink_mocap != "none",
        )
        if kind == "px4" and inst.mocap:
            inst = replace(inst, imu_vibration=px4_imu_vibration)
        check_instance(inst)
        found.append((vehicle.id, inst))
    if not found:
        raise SitlError(f"{show_path}: no vehicle with backend: mavlink")
    return found


def _vibration(text: str) -> float | None:
    if text == "stock":
        return None
    try:
        value = float(text)
    except ValueError:
        value = -1.0
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text!r}: a number from 0 to 1, or stock")
    return value


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("show", type=Path, help="show file whose mavlink vehicles to start")
    parser.add_argument(
        "--run-dir",
        type=Path,
        default=None,
        help="instances' working dirs (default out/<show file name>-sitl)",
    )
    parser.add_argument("--arducopter", help=f"arducopter binary (${ENV_BINARY['ardupilot']})")
    parser.add_argument("--px4", help=f"px4 binary (${ENV_BINARY['px4']})")
    parser.add_argument("--ready-timeout", type=float, default=READY_TIMEOUT_S, metavar="S")
    parser.add_argument(
        "--px4-imu-vibration",
        type=_vibration,
        default=RESEARCH_AIRFRAME_VIBRATION,
        metavar="F|stock",
        help="PX4 SIH vehicles on mocap: armed IMU noise as a fraction of SIH's own, 0-1 "
        "(default 0: a research airframe; needs a px4 from build.py); stock: SIH's own",
    )
    args = parser.parse_args(argv)
    run_dir = args.run_dir or Path("out") / f"{args.show.stem}-sitl"
    procs: list[subprocess.Popen[bytes]] = []
    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt))
    try:
        pairs = show_instances(
            args.show,
            run_dir.resolve(),
            {"ardupilot": args.arducopter, "px4": args.px4},
            args.px4_imu_vibration,
        )
        for vehicle_id, inst in pairs:
            procs.append(start(inst))
            print(
                f"{vehicle_id}: {inst.kind} instance {inst.index}, system id {inst.system_id}, "
                f"{inst.url}, pid {procs[-1].pid}, log {inst.run_dir / 'console.log'}"
            )
        for (vehicle_id, inst), proc in zip(pairs, procs, strict=True):
            waited = wait_ready(inst, proc, args.ready_timeout)
            print(f"{vehicle_id}: ready after {waited:.0f} s", flush=True)
        print("all ready; Ctrl-C stops them", flush=True)
        while all(p.poll() is None for p in procs):
            time.sleep(0.5)
        print("an instance exited; stopping the others", file=sys.stderr)
        return 1
    except SitlError as exc:
        print(f"start.py: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 0
    finally:
        for proc in procs:
            stop(proc)
        if procs:
            print(f"stopped {len(procs)} instance(s)", file=sys.stderr)


if __name__ == "__main__":
    sys.exit(main())
