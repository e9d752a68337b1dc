"""Describe an autopilot SITL instance and pick one that is free on this machine right now.

A show's ``mavlink_url`` says only the kind and where the agent talks to it, any port:

- ``tcp:127.0.0.1:PORT``: ArduCopter, its SERIAL0 listening on PORT (``--serial0 tcp:PORT``;
  ArduPilot takes a port above 1000 as itself, one below as an offset from its base port);
- ``udpin:127.0.0.1:PORT``: PX4 SIH, its offboard link sending to PORT (where the agent listens).

Everything else is the instance number N, which start.py chooses: ArduCopter's ``-I N`` and
PX4's ``-i N`` move the ports an instance binds besides those two (:func:`instance_ports`), PX4's
lock file is per N, and start.py probes each instance on a link of its own at an N-port
(:func:`probe_port`), never on the agent's. :func:`claim` takes the lowest N whose ports are free
now (bind-tested) and locks a file for it; start.py hands that lock to the SITL process, so the
number stays taken exactly as long as the instance runs: two shows, or a show and a test,
started at the same moment get different numbers.

Imported by start.py; free of project imports.
"""

from __future__ import annotations

import fcntl
import math
import os
import socket
import struct
import tempfile
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

from sih import PX4_VIBRATION_PARAM, airframe_params, px4_sih_degrees  # beside this file

Kind = Literal["ardupilot", "px4"]
Protocol = Literal["tcp", "udp"]
ENV_BINARY: dict[str, str] = {
    "ardupilot": "SKYQUILL_ARDUCOPTER_SITL",
    "px4": "SKYQUILL_PX4_SITL",
}
"""Environment variable naming each kind's SITL binary."""
URL_SCHEME: dict[str, Kind] = {"tcp": "ardupilot", "udpin": "px4"}
LOOPBACK_HOSTS = ("127.0.0.1", "localhost")
REFERENCE_LLA = (-35.363261, 149.165230, 584.0)
"""Geodetic point (lat [deg], lon [deg], alt [m]) of the show frame's origin (ArduPilot's CMAC)."""
EARTH_RADIUS_M = 6_378_137.0
MAX_INSTANCES = 20
"""Instance numbers tried, 0 .. 19: below it no two numbers' ports meet (ArduCopter's RC input
5501 + 10*N stays under its serial ports 5760 + 10*N; PX4's probe 14560 + N under its 14580 + N)."""
ARDUPILOT_SERIAL0_BASE = 5760
"""SERIAL0 of instance N without a show port: 5760 + 10*N (the tests' agent link)."""
ARDUPILOT_SERIAL_MIN_ABSOLUTE = 1001
"""ArduPilot takes ``tcp:PORT`` with PORT above 1000 as the port itself (UARTDriver.cpp)."""
PX4_OFFBOARD_REMOTE_BASE = 14540
"""Where PX4's offboard link sends without a show port: 14540 + N (the tests' agent link)."""
PX4_PROBE_BASE = 14560
"""Where PX4 N's GCS link sends, start.py listening (stock: 14550 for every instance)."""
PX4_LOCK_FILE = "/tmp/px4_lock-{n}"
"""PX4 holds a POSIX lock on this file while instance N runs; another ``-i N`` exits at boot."""
FLOCK_FORMAT = "hhqqi4x"
"""Linux's ``struct flock`` on 64-bit machines: type, whence, start, length, pid."""
CLAIM_FILE = "skyquill-sitl-{kind}-{n}.lock"
"""start.py's own lock per instance number, in the temporary directory."""
PX4_PORT_VARIABLES = ("PX4_SYS_ID", "PX4_OFFBOARD_REMOTE_PORT", "PX4_GCS_REMOTE_PORT")
"""What PX4's startup scripts read once scripts/sitl/source_edits.py has edited them."""
MOCAP_PARM = "mocap.parm"
MOCAP_BOOT_PARAMS = {
    "VISO_TYPE": 1.0,
    "EK3_SRC1_POSXY": 6.0,
    "EK3_SRC1_POSZ": 6.0,
    "EK3_SRC1_VELXY": 0.0,
    "EK3_SRC1_VELZ": 0.0,
    "GPS1_TYPE": 0.0,
}
"""ArduCopter parameters that fusing forwarded mocap needs from boot on: VISO_TYPE is read only at
boot; the EKF3 sources (ExternalNav; the agent sets them too, as in
``vehicle_agent/backends/mavlink/params.py``) because a SITL whose GPS gets its fix before the
agent has set them takes its EKF origin from the GPS, then never uses the mocap ("PreArm: Fence
enabled, need position estimate", "Check mag field"): 7 of 10 ArduCopter starts with mocap in
one day, where connecting and setting the parameters took up to 18 s instead of 6.

GPS1_TYPE 0 (no GPS), as ArduPilot's non-GPS navigation setup for an indoor mocap has it: the
EKF origin is then only ever the agent's SET_GPS_GLOBAL_ORIGIN. With the simulated GPS on, four
instances at load 4 let the GPS set the origin first (issue 31): EKF3 keeps the GPS height in
``ekfGpsRefHgt`` to the millimetre and the origin in whole centimetres, and its local z ran
1.0 cm below the mocap it fused for whole flights (every brush pressed 10 mm short, ink
10.5 mm wide against 20 mm, IoU 0.32-0.44), and 2 of 4 instances in 2 of 3 starts died of a
floating point exception in ``NavEKF3_core::Log_Write_XKF4`` (a NaN test ratio) 1 s after the
agent connected."""
PX4_MOCAP_BOOT_PARAMS = {"EKF2_ASP_DELAY": 0.0, "EKF2_DELAY_MAX": 20.0}
"""The same for PX4, given as PX4_PARAM_* variables (vehicle_agent/backends/mavlink/params.py
sets and checks them at connect, and refuses a vehicle that would need a reboot)."""


class SitlError(Exception):
    """A SITL instance could not be described, started or readied; the message says why."""


@dataclass(frozen=True)
class Instance:
    """One SITL process to run."""

    kind: Kind
    """Which autopilot."""
    index: int
    """Instance number N (:func:`instance_ports`), chosen by :func:`claim`."""
    system_id: int
    """MAVLink system id of the autopilot."""
    home_lla: tuple[float, float, float]
    """Start point: latitude [deg], longitude [deg], altitude [m] above mean sea level."""
    binary: Path
    """The arducopter or px4 executable."""
    run_dir: Path
    """Working directory of this instance (created)."""
    agent_port: int
    """The agent's link: ArduCopter's SERIAL0 listener, or where PX4's offboard link sends."""
    mocap: bool = False
    """The agent forwards motion capture: the instance boots with :func:`boot_params` and is
    ready before its EKF has a position (start.py's readiness)."""
    imu_vibration: float | None = None
    """PX4 SIH: its armed IMU noise as a fraction of SIH's own (:data:`PX4_VIBRATION_PARAM`, needs
    a binary built by scripts/sitl/build.py); None leaves SIH's."""
    claim_fd: int | None = None
    """Open file descriptor of this number's lock (:func:`claim`), handed to the process."""

    @property
    def url(self) -> str:
        """Where the agent reaches it (pymavlink and ``mavlink_url`` mean the same here)."""
        return f"{_scheme(self.kind)}:127.0.0.1:{self.agent_port}"

    @property
    def probe_url(self) -> str:
        """start.py's own link to it: ArduCopter's SERIAL2 listener, or the UDP port PX4's GCS
        link sends to."""
        return f"{_scheme(self.kind)}:127.0.0.1:{probe_port(self.kind, self.index)}"


def _scheme(kind: Kind) -> str:
    return next(scheme for scheme, k in URL_SCHEME.items() if k == kind)


def as_kind(text: str) -> Kind:
    """``text`` as a :data:`Kind`; SitlError naming the kinds otherwise."""
    if text == "ardupilot":
        return "ardupilot"
    if text == "px4":
        return "px4"
    raise SitlError(f"unknown autopilot {text!r}: expected ardupilot or px4")


def url_kind_port(url: str) -> tuple[Kind, int]:
    """(kind, agent port) of a SITL vehicle's ``mavlink_url``; SitlError saying what is expected
    otherwise."""
    scheme, _, rest = url.partition(":")
    host, _, port_text = rest.rpartition(":")
    kind = URL_SCHEME.get(scheme)
    port = int(port_text) if port_text.isdigit() else 0
    lowest = ARDUPILOT_SERIAL_MIN_ABSOLUTE if kind == "ardupilot" else 1
    if kind is None or host not in LOOPBACK_HOSTS or not lowest <= port <= 65535:
        raise SitlError(
            f"mavlink_url {url!r} is no SITL instance: expected tcp:127.0.0.1:PORT (ArduCopter's "
            "SERIAL0, PORT 1001-65535) or udpin:127.0.0.1:PORT (where PX4's offboard link sends)"
        )
    return kind, port


def probe_port(kind: Kind, index: int) -> int:
    """start.py's link to instance ``index``: ArduCopter's SERIAL2 (its own ``tcp:3``, MAVLink
    by default), PX4's GCS link (``PX4_GCS_REMOTE_PORT``, source_edits.py)."""
    if kind == "ardupilot":
        return ARDUPILOT_SERIAL0_BASE + 10 * index + 3
    return PX4_PROBE_BASE + index


def default_agent_port(kind: Kind, index: int) -> int:
    """The agent's port of instance ``index`` when no show gives one (tests, probe scripts)."""
    if kind == "ardupilot":
        return ARDUPILOT_SERIAL0_BASE + 10 * index
    return PX4_OFFBOARD_REMOTE_BASE + index


def instance_ports(kind: Kind, index: int) -> tuple[tuple[Protocol, int], ...]:
    """Ports instance ``index`` binds on loopback besides the agent's, and its probe port.

    ArduCopter ``-I N`` (SITL_cmdline.cpp adds 10*N to each): SERIAL1 ``tcp:2`` (5762), SERIAL2
    (5763, the probe), RC input (udp 5501), the simulator's ports (udp 9002/9003, unused by the
    built-in model but moved all the same). PX4 ``-i N``
    (px4-rc.mavlink adds N): the offboard, GCS, payload, gimbal and SIH-display links' local
    ports (udp 14580, 18570, 14280, 13030, 19450) and the probe (14560)."""
    if kind == "ardupilot":
        serials = ARDUPILOT_SERIAL0_BASE + 10 * index
        return (
            ("tcp", serials + 2),
            ("tcp", serials + 3),
            ("udp", 5501 + 10 * index),
            ("udp", 9002 + 10 * index),
            ("udp", 9003 + 10 * index),
        )
    return tuple(("udp", base + index) for base in (14580, 18570, 14280, 13030, 19450, 14560))


def port_free(protocol: Protocol, port: int) -> bool:
    """Whether ``port`` can be bound now on every interface (so no process holds it on any
    address). A TCP port is asked as ArduPilot SITL binds its listeners, with SO_REUSEADDR: the
    TIME_WAIT a finished show leaves on its agent's port for a minute does not hold it (asked
    without, a show started right after another was refused, "tcp:127.0.0.1:25810 is in use")."""
    kind = socket.SOCK_STREAM if protocol == "tcp" else socket.SOCK_DGRAM
    with socket.socket(socket.AF_INET, kind) as sock:
        if protocol == "tcp":
            sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind(("0.0.0.0", port))
        except OSError:
            return False
    return True


def px4_running(index: int) -> bool:
    """Whether a PX4 holds its instance lock ``/tmp/px4_lock-N`` (then ``px4 -i N`` exits at
    boot). Asked as PX4 asks (F_GETLK), taking no lock that a PX4 booting now would see."""
    try:
        fd = os.open(PX4_LOCK_FILE.format(n=index), os.O_RDONLY)
    except FileNotFoundError:
        return False
    try:
        query = struct.pack(FLOCK_FORMAT, fcntl.F_WRLCK, os.SEEK_SET, 0, 0, 0)
        answer = fcntl.fcntl(fd, fcntl.F_GETLK, query)
    finally:
        os.close(fd)
    lock_type: int = struct.unpack(FLOCK_FORMAT, answer)[0]
    return lock_type != fcntl.F_UNLCK


def claim(
    kind: Kind,
    *,
    avoid_ports: Iterable[int] = (),
    default_agent: bool = False,
    lock_dir: Path | None = None,
) -> tuple[int, int]:
    """(instance number, open lock fd) of the lowest N free now: not claimed by another start.py
    (its lock file), no PX4 running as N, and every port of :func:`instance_ports` (with
    ``default_agent``, also :func:`default_agent_port`) free and not in ``avoid_ports`` (the
    show's agent ports). SitlError when none of :data:`MAX_INSTANCES` is."""
    avoid = set(avoid_ports)
    directory = lock_dir or Path(tempfile.gettempdir())
    agent_protocol: Protocol = "tcp" if kind == "ardupilot" else "udp"
    busy: list[str] = []
    for index in range(MAX_INSTANCES):
        fd = _try_lock(directory / CLAIM_FILE.format(kind=kind, n=index))
        if fd is None:
            busy.append(f"{index} (claimed)")
            continue
        ports = instance_ports(kind, index)
        if default_agent:
            ports += ((agent_protocol, default_agent_port(kind, index)),)
        taken = [p for proto, p in ports if p in avoid or not port_free(proto, p)]
        if not taken and not (kind == "px4" and px4_running(index)):
            return index, fd
        os.close(fd)
        busy.append(f"{index} (port {taken[0]} in use)" if taken else f"{index} (px4 running)")
    raise SitlError(f"no free {kind} instance number: {', '.join(busy)}")


def _try_lock(path: Path) -> int | None:
    """An open fd of ``path`` holding its exclusive flock, or None when another process holds
    it. Read-only: another user's lock file locks as well (ports are shared by all users)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except FileNotFoundError:
        fd = os.open(path, os.O_RDONLY | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        os.close(fd)
        return None
    return fd


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


def boot_params(inst: Instance) -> dict[str, float]:
    """Parameters ``inst`` boots with beyond its defaults (start.py reads them back)."""
    if inst.kind == "ardupilot":
        return dict(MOCAP_BOOT_PARAMS) if inst.mocap else {}
    params = dict(PX4_MOCAP_BOOT_PARAMS) if inst.mocap else {}
    return params | airframe_params(inst.imu_vibration)


def command(inst: Instance) -> tuple[list[str], dict[str, str]]:
    """argv and environment of ``inst`` (pure)."""
    lat, lon, alt = inst.home_lla
    env = dict(os.environ)
    if inst.kind == "ardupilot":
        defaults = [str(copter_defaults(inst.binary))]
        if inst.mocap:
            defaults.append(str(inst.run_dir / MOCAP_PARM))
        argv = [str(inst.binary), "--model", "quad", "--speedup", "1", "-I", str(inst.index),
                "--sysid", str(inst.system_id), "--home", f"{lat:.7f},{lon:.7f},{alt:.2f},0",
                "--defaults", ",".join(defaults), "--wipe",
                "--serial0", f"tcp:{inst.agent_port}",
                "--serial2", f"tcp:{probe_port(inst.kind, inst.index)}"]  # fmt: skip
        return argv, env
    env.update(
        PX4_SIM_MODEL="sihsim_quadx",
        PX4_SIMULATOR="sihsim",
        PX4_HOME_LAT=f"{px4_sih_degrees(lat):.10f}",
        PX4_HOME_LON=f"{px4_sih_degrees(lon):.10f}",
        PX4_HOME_ALT=f"{alt:.2f}",
        PX4_SYS_ID=str(inst.system_id),
        PX4_OFFBOARD_REMOTE_PORT=str(inst.agent_port),
        PX4_GCS_REMOTE_PORT=str(probe_port(inst.kind, inst.index)),
    )
    env.update({f"PX4_PARAM_{name}": f"{value:g}" for name, value in boot_params(inst).items()})
    return [str(inst.binary), "-i", str(inst.index), "-d", str(px4_etc(inst.binary))], env


def px4_etc(binary: Path) -> Path:
    """The startup scripts beside a PX4 SITL binary (build/px4_sitl_default/etc)."""
    return binary.resolve().parents[1] / "etc"


def px4_takes_ports(binary: Path) -> bool:
    """Whether the startup scripts of ``binary`` read the variables :func:`command` sets (the
    edits of scripts/sitl/source_edits.py)."""
    init = px4_etc(binary) / "init.d-posix"
    try:
        texts = (init / "rcS").read_text() + (init / "px4-rc.mavlink").read_text()
    except OSError:
        return False
    return all(f"${{{name}" in texts for name in PX4_PORT_VARIABLES)


def mocap_parm_text() -> str:
    """ArduCopter's ``mocap.parm`` (one ``NAME VALUE`` a line)."""
    return "".join(f"{name} {value:g}\n" for name, value in MOCAP_BOOT_PARAMS.items())


def copter_defaults(binary: Path) -> Path:
    """SRC/Tools/autotest/default_params/copter.parm of SRC/build/sitl/bin/arducopter."""
    parents = binary.resolve().parents
    if len(parents) < 4:
        raise SitlError(f"{binary}: expected SRC/build/sitl/bin/arducopter")
    return parents[3] / "Tools" / "autotest" / "default_params" / "copter.parm"


def check_instance(inst: Instance) -> None:
    """SitlError when ``inst`` cannot run as described."""
    if not 1 <= inst.system_id <= 255:
        raise SitlError(f"system id {inst.system_id}: MAVLink takes 1-255")
    if inst.kind == "px4" and not px4_takes_ports(inst.binary):
        raise SitlError(
            f"{px4_etc(inst.binary)} takes no PX4_SYS_ID, PX4_OFFBOARD_REMOTE_PORT and "
            'PX4_GCS_REMOTE_PORT: build it with scripts/sitl/build.py (README, "Real autopilot '
            'SITL")'
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
        defaults = copter_defaults(inst.binary)
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
