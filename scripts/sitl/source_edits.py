"""The edits scripts/sitl/build.py makes to an ArduPilot or PX4 source checkout before building.

Each edit replaces one exact piece of text that must occur once in its file; applying it again
finds its result and changes nothing, so a checkout can be built again. An edit whose text is not
found (another release moved it) stops the build with the file and what was expected: better no
binary than one that listens on every interface.

- **Loopback only.** Both SITLs bind their MAVLink and simulator sockets to every interface
  (INADDR_ANY): anyone on the network could command the simulated vehicle. Every listener the
  shows use is bound to 127.0.0.1 instead.
- **PX4 board options** (``boards/px4/sitl/default.px4board``): ``uxrce_dds_client`` clones
  Micro-XRCE-DDS from the network while building and ``gyro_fft`` needs CMSIS-DSP sources that
  some checkouts lack; a show flies without either.
- **PX4 SIH's airframe vibration as a parameter.** SIH adds accelerometer noise of std 0.5 / 1.7 /
  1.4 m/s^2 and gyro noise of 0.14 / 0.07 / 0.03 rad/s (x / y / z) whenever the motors turn: a
  vibrating consumer airframe, hard-coded (sih.cpp, "reconstruct_sensors_signals"). Measured
  here, EKF2 on mocap then holds a hover only to 14 / 11 / 10 mm and the brush never settles
  within 1 cm. The papers' vehicles are soft-mounted research airframes on motion capture.
  ``SIH_IMU_VIB`` (new, default 1: unchanged) scales the armed noise between SIH's own disarmed
  level (0: 0.1 m/s^2 and 0.01 rad/s on every axis) and the stock level (1); the same number of
  random draws either way. scripts/sitl/start.py sets it for vehicles on mocap.
- **PX4's truth stamped with its own time.** HIL_STATE_QUATERNION carries SIH's true state to the
  agent, which makes the show's mocap of it; PX4 leaves its ``time_usec`` 0, so the agent took
  each sample's time from the last ATTITUDE (a stream of its own) and from when it arrived.
  ``time_usec`` is now the truth's sample time (``timestamp_sample``, PX4's clock since boot, as
  the message defines it); why: docs/sitl.md.
- **PX4's truth to the float.** HIL_STATE_QUATERNION carries the position in whole 1e-7 degrees
  (1.1 cm) and the velocity in whole cm/s, truncated: smoothed, the mocap made of it was still
  0.7-1.2 mm off the truth across the path, its velocity 4-5.5 mm/s between 0.2 and 1 Hz. The
  same stream now also sends the truth's local position, velocity and acceleration as floats in
  a LOCAL_POSITION_NED_COV (same ``time_usec``, ``estimator_type`` UNKNOWN, covariance
  unknown), a message PX4 sends nowhere else; the agent's truth takes its position from it.
  Measured (issue 31, docs/sitl.md): the mocap 0.22-0.25 mm across the path (the show's noise),
  and the research airframe's IoU median 0.72 -> 0.82.
- **PX4's system id and two UDP ports from the environment.** ``px4 -i N`` forces MAV_SYS_ID
  N + 1 (after the PX4_PARAM_* overrides, so those cannot change it), sends its offboard link to
  14540 + N and its GCS link to 14550, one port for every instance on the machine: two shows, or
  a show and a test, could not run side by side nor say where their autopilots are. When set,
  ``PX4_SYS_ID``, ``PX4_OFFBOARD_REMOTE_PORT`` and ``PX4_GCS_REMOTE_PORT`` give them instead
  (start.py sets all three); unset, PX4 starts as shipped.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Literal

Outcome = Literal["applied", "present"]


class EditError(Exception):
    """A source file is missing or does not contain the text an edit expects; the message says
    which file and what."""


@dataclass(frozen=True)
class Edit:
    """Replace ``before`` (exactly once in the file) with ``after``."""

    path: str
    """File relative to the checkout's root."""
    before: str
    after: str
    why: str
    """One line for the build's log."""


def state(root: Path, edit: Edit) -> Outcome | None:
    """ "present" when ``edit``'s result is in its file, None when it can be applied; EditError
    when the file is missing or does not hold ``edit.before`` exactly once."""
    path = root / edit.path
    if not path.is_file():
        raise EditError(f"{path}: no such file (is {root} the right checkout?)")
    text = path.read_text(encoding="utf-8")
    if edit.after in text:
        return "present"
    found = text.count(edit.before)
    if found != 1:
        first_line = edit.before.strip().splitlines()[0]
        raise EditError(
            f"{path}: expected exactly one {first_line!r}, found {found} "
            f"(a release this script does not know; edit by hand: {edit.why})"
        )
    return None


def apply_edits(root: Path, edits: tuple[Edit, ...]) -> list[tuple[Edit, Outcome]]:
    """Apply every edit under ``root``, each "applied" or already "present"; all are checked
    before any file is written, so a checkout of another release is left untouched."""
    for edit in edits:
        state(root, edit)
    done: list[tuple[Edit, Outcome]] = []
    for edit in edits:
        if state(root, edit) == "present":
            done.append((edit, "present"))
            continue
        path = root / edit.path
        path.write_text(path.read_text(encoding="utf-8").replace(edit.before, edit.after), "utf-8")
        done.append((edit, "applied"))
    return done


LOOPBACK = "htonl(INADDR_LOOPBACK)"

ARDUPILOT_EDITS = (
    Edit(
        "libraries/AP_HAL_SITL/UARTDriver.cpp",
        "        _listen_sockaddr.sin_family = AF_INET;\n",
        "        _listen_sockaddr.sin_family = AF_INET;\n"
        f"        _listen_sockaddr.sin_addr.s_addr = {LOOPBACK}; // skyquill: loopback only\n",
        "SERIALn tcp listeners (5760 + 10*I ...) on 127.0.0.1",
    ),
    Edit(
        "libraries/AP_HAL_SITL/SITL_State.cpp",
        "    sockaddr.sin_addr.s_addr = htonl(INADDR_ANY);\n",
        f"    sockaddr.sin_addr.s_addr = {LOOPBACK}; // skyquill: loopback only\n",
        "multicast-state servo input (20722 + I) on 127.0.0.1",
    ),
    Edit(
        "libraries/AP_RCProtocol/AP_RCProtocol_UDP.cpp",
        '    if (!rc_in.bind("0.0.0.0", sitl->rcin_port)) {\n',
        '    if (!rc_in.bind("127.0.0.1", sitl->rcin_port)) { // skyquill: loopback only\n',
        "SITL RC input (udp 5501 + 10*I: sticks from anyone who sends) on 127.0.0.1",
    ),
)
"""ArduPilot 4.5-4.7 (checked on 4.7.0-dev)."""

_SIH_NOISE_STOCK = (
    "\t\taccel_noise = noiseGauss3f(0.5f, 1.7f, 1.4f);\n"
    "\t\tgyro_noise = noiseGauss3f(0.14f, 0.07f, 0.03f);\n"
)
_SIH_NOISE_SCALED = (
    "\t\t// skyquill: SIH_IMU_VIB from the disarmed noise (0) to SIH's own (1)\n"
    "\t\tconst float vib = math::constrain(_sih_imu_vib.get(), 0.f, 1.f);\n"
    "\t\taccel_noise = noiseGauss3f(0.1f + vib * 0.4f, 0.1f + vib * 1.6f, 0.1f + vib * 1.3f);\n"
    "\t\tgyro_noise = noiseGauss3f(0.01f + vib * 0.13f, 0.01f + vib * 0.06f, "
    "0.01f + vib * 0.02f);\n"
)
_SIH_PARAM_LAST = "\t\t(ParamInt<px4::params::SIH_VEHICLE_TYPE>) _sih_vtype\n\t)"
_SIH_PARAM_DEFINITION = """
/**
 * Airframe vibration (skyquill)
 *
 * Armed IMU noise as a fraction of SIH's own: 1 is SIH's vibrating airframe (accelerometer
 * std 0.5 / 1.7 / 1.4 m/s^2), 0 its disarmed level (0.1 m/s^2, 0.01 rad/s), a soft-mounted
 * research airframe.
 *
 * @min 0
 * @max 1
 * @decimal 2
 * @group Simulation In Hardware
 */
PARAM_DEFINE_FLOAT(SIH_IMU_VIB, 1.0f);
"""
_SIH_PARAM_ANCHOR = "PARAM_DEFINE_INT32(SIH_VEHICLE_TYPE, 0);\n"
_SIH = "src/modules/simulation/simulator_sih/"
_POSIX_INIT = "ROMFS/px4fmu_common/init.d-posix/"
_TRUTH_STREAM = "src/modules/mavlink/streams/HIL_STATE_QUATERNION.hpp"
_TRUTH_LATITUDE = "\t\t\tmsg.lat = gpos.lat * 1e7;\n"
_TRUTH_SENT = "\t\t\tmavlink_msg_hil_state_quaternion_send_struct(_mavlink->get_channel(), &msg);\n"
_EXACT_TRUTH_SENT = (
    "\t\t\t// skyquill: the same truth's position and velocity as floats, beside their whole\n"
    "\t\t\t// 1e-7 degrees and cm/s above; the same time, no covariance (not an estimate)\n"
    "\t\t\tmavlink_local_position_ned_cov_t exact{};\n"
    "\t\t\texact.time_usec = lpos.timestamp_sample;\n"
    "\t\t\texact.estimator_type = MAV_ESTIMATOR_TYPE_UNKNOWN;\n"
    "\t\t\texact.x = lpos.x;\n"
    "\t\t\texact.y = lpos.y;\n"
    "\t\t\texact.z = lpos.z;\n"
    "\t\t\texact.vx = lpos.vx;\n"
    "\t\t\texact.vy = lpos.vy;\n"
    "\t\t\texact.vz = lpos.vz;\n"
    "\t\t\texact.ax = lpos.ax;\n"
    "\t\t\texact.ay = lpos.ay;\n"
    "\t\t\texact.az = lpos.az;\n"
    "\t\t\texact.covariance[0] = NAN;\n"
    "\t\t\tmavlink_msg_local_position_ned_cov_send_struct(_mavlink->get_channel(), &exact);\n"
)
_TRUTH_SIZE = (
    "\t\t\treturn MAVLINK_MSG_ID_HIL_STATE_QUATERNION_LEN + MAVLINK_NUM_NON_PAYLOAD_BYTES;\n"
)
_EXACT_TRUTH_SIZE = (
    "\t\t\t// skyquill: and the truth to the float (below)\n"
    "\t\t\treturn MAVLINK_MSG_ID_HIL_STATE_QUATERNION_LEN + MAVLINK_NUM_NON_PAYLOAD_BYTES\n"
    "\t\t\t       + MAVLINK_MSG_ID_LOCAL_POSITION_NED_COV_LEN + MAVLINK_NUM_NON_PAYLOAD_BYTES;\n"
)
_OFFBOARD_REMOTE_STOCK = (
    '[ "$px4_instance" -gt 9 ] && udp_offboard_port_remote=14549 # use the same ports for more '
    "than 10 instances to avoid port overlaps\n"
)
_GCS_LINK_STOCK = "mavlink start -x -u $udp_gcs_port_local -r 4000000 -f\n"
_SYS_ID_STOCK = "param set MAV_SYS_ID $((px4_instance+1))\n"

PX4_EDITS = (
    Edit(
        "src/modules/mavlink/mavlink_main.cpp",
        "\t_myaddr.sin_addr.s_addr = htonl(INADDR_ANY);\n",
        f"\t_myaddr.sin_addr.s_addr = {LOOPBACK}; // skyquill: loopback only\n",
        "MAVLink UDP ports (14580 + I, 18570 + I) on 127.0.0.1",
    ),
    Edit(
        "src/modules/simulation/simulator_mavlink/SimulatorMavlink.cpp",
        "\t_myaddr.sin_addr.s_addr = htonl(INADDR_ANY);\n",
        f"\t_myaddr.sin_addr.s_addr = {LOOPBACK}; // skyquill: loopback only\n",
        "simulator_mavlink port (4560 + I; SIH does not use it) on 127.0.0.1",
    ),
    Edit(
        "boards/px4/sitl/default.px4board",
        "CONFIG_MODULES_GYRO_FFT=y\n",
        "CONFIG_MODULES_GYRO_FFT=n\n",
        "gyro_fft off (needs CMSIS-DSP sources)",
    ),
    Edit(
        "boards/px4/sitl/default.px4board",
        "CONFIG_MODULES_UXRCE_DDS_CLIENT=y\n",
        "CONFIG_MODULES_UXRCE_DDS_CLIENT=n\n",
        "uxrce_dds_client off (its build clones from the network)",
    ),
    Edit(
        _SIH + "sih.hpp",
        _SIH_PARAM_LAST,
        "\t\t(ParamInt<px4::params::SIH_VEHICLE_TYPE>) _sih_vtype,\n"
        "\t\t(ParamFloat<px4::params::SIH_IMU_VIB>) _sih_imu_vib\n\t)",
        "SIH_IMU_VIB read by SIH",
    ),
    Edit(
        _SIH + "sih_params.c",
        _SIH_PARAM_ANCHOR,
        _SIH_PARAM_ANCHOR + _SIH_PARAM_DEFINITION,
        "SIH_IMU_VIB defined (default 1: SIH unchanged)",
    ),
    Edit(
        _SIH + "sih.cpp",
        _SIH_NOISE_STOCK,
        _SIH_NOISE_SCALED,
        "SIH's armed IMU noise scaled by SIH_IMU_VIB",
    ),
    Edit(
        _TRUTH_STREAM,
        _TRUTH_LATITUDE,
        "\t\t\t// skyquill: the truth's own time (PX4 leaves it 0)\n"
        "\t\t\tmsg.time_usec = lpos.timestamp_sample;\n" + _TRUTH_LATITUDE,
        "HIL_STATE_QUATERNION stamped with the truth's sample time",
    ),
    Edit(
        _TRUTH_STREAM,
        _TRUTH_SENT,
        _TRUTH_SENT + _EXACT_TRUTH_SENT,
        "the truth's position and velocity as floats (LOCAL_POSITION_NED_COV)",
    ),
    Edit(
        _TRUTH_STREAM,
        _TRUTH_SIZE,
        _EXACT_TRUTH_SIZE,
        "the truth stream's size counts both messages",
    ),
    Edit(
        _POSIX_INIT + "rcS",
        _SYS_ID_STOCK,
        "# skyquill: PX4_SYS_ID, when set, is the system id (else instance + 1)\n"
        "param set MAV_SYS_ID ${PX4_SYS_ID:-$((px4_instance+1))}\n",
        "MAV_SYS_ID from $PX4_SYS_ID when set",
    ),
    Edit(
        _POSIX_INIT + "px4-rc.mavlink",
        _OFFBOARD_REMOTE_STOCK,
        _OFFBOARD_REMOTE_STOCK
        + "# skyquill: PX4_OFFBOARD_REMOTE_PORT, when set, is where the offboard link sends\n"
        "udp_offboard_port_remote=${PX4_OFFBOARD_REMOTE_PORT:-$udp_offboard_port_remote}\n",
        "offboard link's remote port from $PX4_OFFBOARD_REMOTE_PORT when set",
    ),
    Edit(
        _POSIX_INIT + "px4-rc.mavlink",
        _GCS_LINK_STOCK,
        "# skyquill: PX4_GCS_REMOTE_PORT, when set, is where the GCS link sends (else 14550)\n"
        "mavlink start -x -u $udp_gcs_port_local -r 4000000 -f "
        "${PX4_GCS_REMOTE_PORT:+-o $PX4_GCS_REMOTE_PORT}\n",
        "GCS link's remote port from $PX4_GCS_REMOTE_PORT when set",
    ),
)
"""PX4 v1.16 (SIH quadrotor)."""
