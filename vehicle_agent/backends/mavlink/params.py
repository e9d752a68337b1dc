"""Autopilot parameters a show depends on: chosen in pure code, set and read back over MAVLink.

At connect the backend sets each :class:`ParamSpec` with PARAM_SET, waits for the autopilot's
PARAM_VALUE, then asks again with PARAM_REQUEST_READ and compares (set and read again, up to the
channel's attempts, when the value read back is another): a parameter that is unknown, never
answered or answered with another value every time makes the vehicle unusable
(:class:`ParamError`).

ArduPilot carries every value as a float (integers cast); PX4 packs integer parameters bytewise
into the float field (MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE): :func:`encode_value` and
:func:`decode_value` know both.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import struct
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

from showfile.geofence import Geofence, Vec3
from vehicle_agent.backends.mavlink.errors import MavlinkError
from vehicle_agent.backends.mavlink.link import MavlinkLink
from vehicle_agent.backends.mavlink.state import LinkState

MAV_PARAM_TYPE_INT8, MAV_PARAM_TYPE_INT16, MAV_PARAM_TYPE_INT32, MAV_PARAM_TYPE_REAL32 = 2, 4, 6, 9
INTEGER_TYPES = frozenset(range(1, 9))
"""MAV_PARAM_TYPE_UINT8 .. INT64."""
ARDUPILOT_FENCE_CIRCLE_AND_ALT_MAX = 3
"""ArduCopter FENCE_TYPE: bit 0 maximum altitude, bit 1 circle around home."""
ARDUPILOT_FENCE_ACTION_LAND = 2
PX4_GF_ACTION_LAND = 5
ARDUPILOT_SOURCE_EXTERNAL_NAV = 6
"""EK3_SRC*_POS*/VEL*/YAW: ExternalNav."""
PX4_DELAY_MAX_MS = 20.0
"""EKF2_DELAY_MAX (read at boot): how far behind now EKF2 fuses, in [ms]. Its default 200 ms
suits a GPS; mocap arrives within milliseconds, and the 200 ms the output predictor must bridge
on the IMU alone left PX4 SIH's estimate 10-44 cm off the truth in a take-off and transit
(2-6 cm at 100 ms), so the position loop chased an estimate that lagged the vehicle. EKF2 raises
it at boot to its longest sensor delay: the airspeed's 100 ms goes to 0 with it."""
PX4_OUTPUT_TAU_POS_S = 0.1
"""EKF2_TAU_POS in [s] (its minimum; default 0.25): how fast the output predictor, which carries
the fused state to now on the IMU, pulls its position to it. SIH, a take-off and transit with
EKF2_DELAY_MAX 20 ms: estimate minus truth RMS 1.4 / 0.5 / 3.1 cm (x, y, z)."""
PX4_OUTPUT_TAU_VEL_S = 0.1
"""EKF2_TAU_VEL in [s] at most (default 0.25; PX4 1.16 sets no minimum, EKF2 bounds it by its 10
ms update): how fast the output predictor pulls its velocity to the fused one; between updates it
integrates the accelerometer. A smaller value the autopilot already has is kept (an airframe
whose accelerometer is noisier than the mocap's velocity wants it smaller: SIH's stock airframe
0.03, ``scripts/sitl/sih.py``), as it is a property of the airframe, not of the show. For all
PX4s at 0.03 (2026-11-30) the research airframe's 一 at stretch 2 (``tests/test_sitl_writing.py``,
quiet) wrote IoU 0.57-0.69 in six runs (median 0.63, three below the test's 0.6) against
0.56-0.73 in eight (0.68, one below) at 0.1, with the same RMSE (7.0-10.1 against 7.1-10.0 mm):
suggestive, not proven; with a clean accelerometer the velocity is better carried on it."""
PX4_EV_CTRL_POSITION_3D = 3
"""EKF2_EV_CTRL bits 0 and 1: fuse external-vision horizontal and vertical position."""
PX4_EV_CTRL_VELOCITY = 4
"""EKF2_EV_CTRL bit 2: fuse external-vision velocity (ODOMETRY carries it)."""
PX4_EV_CTRL_YAW = 8
"""EKF2_EV_CTRL bit 3: take the heading from the mocap (the compass is then left out), as PX4's
guide to motion capture has it. Without it EKF2 (v1.16, ev_height_control.cpp) turns every vision
position by a low-passed rotation from the vision's attitude to its own (``_ev_q_error_filt``),
roll and pitch included, so its own tilt error enters the height as tilt times the distance from
the local origin. Measured on SIH (issue 31): two vehicles 1.2-1.8 m from their origins flew 0-6
and 12-14 mm above what EKF2 took from the mocap, and the second one's brush pressed 0.9-2.4 mm
instead of 15. With the yaw fused EKF2 keeps the vision's frame and turns nothing."""
PX4_MOCAP_VELOCITY_NOISE_MPS = 0.02
"""EKF2_EVV_NOISE in [m/s] (default 0.1): the velocity of poses 20 ms apart with the show's
0.2 mm mocap noise is ~0.014 m/s off."""
PX4_MOCAP_VELOCITY_GATE_SD = 5.0
"""EKF2_EVV_GATE in standard deviations (default 3). PX4 1.16 refuses to arm while the velocity
innovation test ratio, innovation^2 / (gate^2 * variance), exceeds 0.5 (EKF2.cpp,
kMinTestRatioPreflight). With the mocap's velocity trusted to EKF2_EVV_NOISE, SIH on the ground
after a landing showed ratios 0.05-0.6 flipping every few seconds ("Preflight Fail: horizontal
velocity unstable"), and arming refused in the moment it passed. The ratio goes as 1/gate^2: 5
SD puts those readings at 0.02-0.22; an innovation still needs 3.5 SD to hold arming."""
PX4_MOCAP_ACC_NOISE_MPS2 = 1.0
"""EKF2_ACC_NOISE in [m/s^2] (default 0.35): how far EKF2 lets the accelerometer carry the state
between mocap samples. PX4 SIH's accelerometer is a vibrating airframe's (std 0.5 / 1.7 /
1.4 m/s^2 armed): with the mocap's velocity fused, estimate minus truth 9.7 / 1.6 / 4.6 mm RMS
(x, y, z in a hover) at the default, 2.8 / 1.3 / 3.1 mm at 1.0."""
PX4_HGT_REF_VISION = 3
"""EKF2_HGT_REF: external vision. EKF2 (v1.16) takes the vision's z as down from altitude 0, so
the agent sets the EKF origin at altitude 0 (``MocapForwarder.set_ekf_origin``): its local z is
then the mocap's. Measured on SIH, one take-off to 1.05 m: the barometer as reference left the
height 0.28 m off the truth (estimate 0.96 m, truth 1.24 m); vision with the origin at the home
altitude read z = +584 m NED on the ground; vision with the origin at 0: within 2-8 cm."""

ARDUPILOT_MOCAP_NOISE_M = 0.01
"""VISO_POS_M_NSE in [m]: the ExternalNav position noise EKF3 assumes (default 0.2; its horizontal
fusion takes down to 0.01, below the 0.1 its documentation lists). With the mocap's timing below,
ArduCopter SITL writing 一 and 十: estimate minus truth RMS 6-9 mm at 0.1 and 3-4 mm at 0.01."""
ARDUPILOT_OUTPUT_TAU_CS = 10
"""EK3_TAU_OUTPUT in [cs] (its minimum; default 25): how fast the output predictor is pulled to the
fused state, as PX4_OUTPUT_TAU_POS_S."""
ARDUPILOT_MOCAP_DELAY_MS = 0
"""VISO_DELAY_MS: ArduPilot places each VISION_POSITION_ESTIMATE at its own timestamp (the capture
time, the clock offset learnt from the link) and then takes VISO_DELAY_MS off again (default
10 ms): the estimate ran 4-5 mm ahead of the truth along a stroke at 0.2 m/s; at 0, 1 mm."""

Flavor = Literal["ardupilot", "px4"]


class ParamError(MavlinkError):
    """A parameter could not be set to the value the show needs."""


@dataclass(frozen=True)
class ParamSpec:
    """One parameter and the value the show needs."""

    name: str
    """Parameter id (at most 16 characters)."""
    value: float
    """The value to set."""
    param_type: int
    """MAV_PARAM_TYPE of the parameter on that autopilot."""
    why: str = ""
    """Why the show needs it (for the error message)."""
    needs_reboot: bool = False
    """The autopilot reads it only at boot: found otherwise, it is set and the vehicle refused
    until rebooted (SITL: give it in the instance's defaults)."""
    at_most: bool = False
    """The show needs no more than ``value``: a smaller value the autopilot has is kept (one its
    airframe was tuned to), a larger one is set to ``value``."""


@dataclass(frozen=True)
class FenceSpec:
    """The autopilot's own fence around its home: a cylinder."""

    radius_m: float
    """Largest horizontal distance from home in [m]."""
    ceiling_m: float
    """Largest height above home in [m]."""


def autopilot_fence(fence: Geofence, home_m_enu: Vec3, margin_m: float) -> FenceSpec:
    """The autopilot's cylinder around its home that contains ``fence`` with ``margin_m`` to
    spare (the autopilot's fence is the second line: the agent's own acts first)."""
    radius = fence.radius_around_m((home_m_enu[0], home_m_enu[1])) + margin_m
    return FenceSpec(radius_m=radius, ceiling_m=fence.ceiling_z_m - home_m_enu[2] + margin_m)


ARDUPILOT_TRACKING = (
    ("PSC_POSXY_P", 3.0),
    ("PSC_VELXY_P", 6.0),
    ("PSC_VELXY_I", 3.0),
    ("PSC_JERK_XY", 20.0),
)
"""ArduCopter's horizontal position loop for writing: three times its default P-PI cascade
(1, 2, 1) and four times its jerk limit (5 m/s^3), so a stroke's target is shaped less and
followed closer. On ArduCopter SITL with mocap, 一's pen-down RMSE 39 mm at the defaults, 17 mm
at twice them. Three times gave no more then (18 mm), while the truth fed back as mocap was
quantized to a centimetre. With it smoothed (``truth_filter``), the Airshow show (four
vehicles, 12 held-out characters, quiet): the brush's error across the stroke RMS 3.2-5.6 mm at
twice, 2.6-3.4 mm at three times; IoU median 0.69 -> 0.75, worst 0.65 -> 0.71, and each
vehicle's later jobs at a faster pace the model chose (stretch 1.9-2.3 against 2.6-3.5)
(issue 31)."""
PX4_TRACKING = (
    ("MPC_XY_P", 2.85),
    ("MPC_XY_VEL_P_ACC", 5.4),
    ("MPC_XY_VEL_I_ACC", 1.6),
    ("MPC_Z_P", 2.0),
    ("MPC_Z_VEL_P_ACC", 6.0),
)
"""PX4's position loop for writing: three times its default P-PI cascade (0.95, 1.8; the
integral 1.6, four times its 0.4), beyond the ranges PX4 documents for a real airframe (2 and 5);
MPC_Z_P 2 and MPC_Z_VEL_P_ACC 6 (defaults 1 and 4). Measured on PX4 1.16 SIH on mocap
(ODOMETRY), research airframe (SIH_IMU_VIB 0). While EKF2 turned the vision by its own tilt
error (``EKF2_EV_CTRL`` without the heading, until 2026-11-30), stiffer loops wrote worse: 一 / 十
pen-down RMSE at twice the defaults 5.5-8.6 / 9.3-10.6 mm, at 2.5 times 10.0-13.2 / 9.8-11.7 mm,
at 3.5 times 13.0 / 11.8 mm; 1.3 times lagged and wandered (37 / 26 mm). Since then, G 火 R
written by one vehicle on a 0.6 m board (bench_mavlink): twice RMSE median 8.4 mm, IoU median
0.66, worst 0.41; three times 6.9 mm, 0.70, 0.65; four times 9.5 mm, 0.62, 0.56. The
``shows/sitl-px4.yaml`` show (two vehicles, 12 held-out characters, quiet): twice 8.9 mm, IoU
0.70, worst 0.47; three times 6.7 mm, 0.71, 0.64. The error left is along the stroke in
proportion to the plan's acceleration, about a / (MPC_XY_P * MPC_XY_VEL_P_ACC) (0.15 s^2 at
twice, 0.08 s^2 at three times): docs/sitl.md."""


def show_params(
    flavor: Flavor, *, setpoint_timeout_s: float, fence: FenceSpec | None
) -> list[ParamSpec]:
    """What a show needs of this autopilot: setpoint timeout, yaw left alone (ArduPilot),
    writing-grade tracking, its own fence as a second line."""
    if flavor == "px4":
        specs = [ParamSpec("COM_OF_LOSS_T", setpoint_timeout_s, MAV_PARAM_TYPE_REAL32,
                           why="offboard loss timeout")]  # fmt: skip
        specs += [ParamSpec(name, value, MAV_PARAM_TYPE_REAL32, why="writing-grade tracking")
                  for name, value in PX4_TRACKING]  # fmt: skip
        if fence is not None:
            specs += [
                ParamSpec("GF_MAX_HOR_DIST", fence.radius_m, MAV_PARAM_TYPE_REAL32, why="fence"),
                ParamSpec("GF_MAX_VER_DIST", fence.ceiling_m, MAV_PARAM_TYPE_REAL32, why="fence"),
                ParamSpec("GF_ACTION", PX4_GF_ACTION_LAND, MAV_PARAM_TYPE_INT32, why="fence"),
            ]
        return specs
    specs = [
        ParamSpec("GUID_TIMEOUT", setpoint_timeout_s, MAV_PARAM_TYPE_REAL32,
                  why="stop when setpoints stop"),
        ParamSpec("WP_YAW_BEHAVIOR", 0, MAV_PARAM_TYPE_INT8, why="yaw not turned by the autopilot"),
    ]  # fmt: skip
    specs += [ParamSpec(name, value, MAV_PARAM_TYPE_REAL32, why="writing-grade tracking")
              for name, value in ARDUPILOT_TRACKING]  # fmt: skip
    if fence is not None:
        specs += [
            ParamSpec("FENCE_TYPE", ARDUPILOT_FENCE_CIRCLE_AND_ALT_MAX, MAV_PARAM_TYPE_INT8,
                      why="fence"),
            ParamSpec("FENCE_RADIUS", fence.radius_m, MAV_PARAM_TYPE_REAL32, why="fence"),
            ParamSpec("FENCE_ALT_MAX", fence.ceiling_m, MAV_PARAM_TYPE_REAL32, why="fence"),
            ParamSpec("FENCE_ACTION", ARDUPILOT_FENCE_ACTION_LAND, MAV_PARAM_TYPE_INT8,
                      why="fence"),
            ParamSpec("FENCE_ENABLE", 1, MAV_PARAM_TYPE_INT8, why="fence"),
        ]  # fmt: skip
    return specs


def mocap_params(flavor: Flavor, *, with_velocity: bool = False) -> list[ParamSpec]:
    """What fusing forwarded motion capture needs: ArduPilot's EKF3 takes position (and, with
    ``with_velocity``, the velocity ODOMETRY carries) from ExternalNav (VISO_TYPE 1, MAVLink;
    read at boot) with yaw from its compass; PX4's EKF2 fuses external-vision position, heading (and
    velocity) with GPS off (a consumer GPS next to it would pull the estimate off by decimetres),
    height from the vision too (see PX4_HGT_REF_VISION)."""
    if flavor == "px4":
        return _px4_mocap_params(with_velocity)
    velocity_source = ARDUPILOT_SOURCE_EXTERNAL_NAV if with_velocity else 0
    return [
        ParamSpec("VISO_TYPE", 1, MAV_PARAM_TYPE_INT8, why="mocap over MAVLink",
                  needs_reboot=True),
        ParamSpec("EK3_SRC1_POSXY", ARDUPILOT_SOURCE_EXTERNAL_NAV, MAV_PARAM_TYPE_INT8,
                  why="horizontal position from mocap"),
        ParamSpec("EK3_SRC1_POSZ", ARDUPILOT_SOURCE_EXTERNAL_NAV, MAV_PARAM_TYPE_INT8,
                  why="height from mocap"),
        ParamSpec("EK3_SRC1_VELXY", velocity_source, MAV_PARAM_TYPE_INT8,
                  why="velocity from mocap (odometry) or none, never the GPS"),
        ParamSpec("EK3_SRC1_VELZ", velocity_source, MAV_PARAM_TYPE_INT8,
                  why="velocity from mocap (odometry) or none, never the GPS"),
        ParamSpec("VISO_POS_M_NSE", ARDUPILOT_MOCAP_NOISE_M, MAV_PARAM_TYPE_REAL32,
                  why="mocap is millimetre-grade"),
        ParamSpec("VISO_DELAY_MS", ARDUPILOT_MOCAP_DELAY_MS, MAV_PARAM_TYPE_INT16,
                  why="the mocap's timestamps carry its latency"),
        ParamSpec("EK3_TAU_OUTPUT", ARDUPILOT_OUTPUT_TAU_CS, MAV_PARAM_TYPE_INT8,
                  why="the estimate follows the mocap closely"),
    ]  # fmt: skip


def _px4_mocap_params(with_velocity: bool) -> list[ParamSpec]:
    ev_ctrl = (
        PX4_EV_CTRL_POSITION_3D | PX4_EV_CTRL_YAW | (PX4_EV_CTRL_VELOCITY if with_velocity else 0)
    )
    specs = [
        ParamSpec("EKF2_EV_CTRL", ev_ctrl, MAV_PARAM_TYPE_INT32, why="fuse mocap"),
        ParamSpec("EKF2_HGT_REF", PX4_HGT_REF_VISION, MAV_PARAM_TYPE_INT32,
                  why="height from mocap (the barometer wanders by decimetres)"),
        ParamSpec("EKF2_GPS_CTRL", 0, MAV_PARAM_TYPE_INT32, why="position from mocap only"),
        ParamSpec("EKF2_EVP_NOISE", 0.01, MAV_PARAM_TYPE_REAL32,
                  why="mocap is millimetre-grade (its smallest value)"),
        ParamSpec("EKF2_TAU_POS", PX4_OUTPUT_TAU_POS_S, MAV_PARAM_TYPE_REAL32,
                  why="the estimate follows the mocap closely"),
        ParamSpec("EKF2_TAU_VEL", PX4_OUTPUT_TAU_VEL_S, MAV_PARAM_TYPE_REAL32,
                  why="the velocity follows the mocap's", at_most=True),
        ParamSpec("EKF2_RNG_CTRL", 0, MAV_PARAM_TYPE_INT32,
                  why="no range-finder height: over the board it measures the table"),
        ParamSpec("EKF2_ASP_DELAY", 0.0, MAV_PARAM_TYPE_REAL32,
                  why="no airspeed sensor (EKF2 raises EKF2_DELAY_MAX to each delay)"),
        ParamSpec("EKF2_DELAY_MAX", PX4_DELAY_MAX_MS, MAV_PARAM_TYPE_REAL32,
                  why="fuse the mocap as it arrives", needs_reboot=True),
    ]  # fmt: skip
    if with_velocity:
        specs += [
            ParamSpec("EKF2_EVV_NOISE", PX4_MOCAP_VELOCITY_NOISE_MPS, MAV_PARAM_TYPE_REAL32,
                      why="velocity differenced from millimetre-grade poses"),
            ParamSpec("EKF2_EVV_GATE", PX4_MOCAP_VELOCITY_GATE_SD, MAV_PARAM_TYPE_REAL32,
                      why="its pre-arm velocity check holds still on the ground"),
            ParamSpec("EKF2_ACC_NOISE", PX4_MOCAP_ACC_NOISE_MPS2, MAV_PARAM_TYPE_REAL32,
                      why="the mocap, not the vibrating accelerometer, carries the motion"),
        ]  # fmt: skip
    return specs


def encode_value(flavor: Flavor, value: float, param_type: int) -> float:
    """The float to put in PARAM_SET.param_value."""
    if flavor == "px4" and param_type in INTEGER_TYPES:
        return float(struct.unpack("<f", struct.pack("<i", round(value)))[0])
    return float(value)


def decode_value(flavor: Flavor, raw: float, param_type: int) -> float:
    """The parameter's value from PARAM_VALUE.param_value."""
    if flavor == "px4" and param_type in INTEGER_TYPES:
        return float(struct.unpack("<i", struct.pack("<f", raw))[0])
    return float(raw)


def same_value(a: float, b: float) -> bool:
    """Equal as a float32 parameter can hold them."""
    return math.isclose(a, b, rel_tol=1e-6, abs_tol=1e-6)


class ParamChannel:
    """PARAM_SET / PARAM_REQUEST_READ answered by PARAM_VALUE, with retries."""

    def __init__(
        self,
        link: Callable[[], MavlinkLink],
        state: LinkState,
        flavor: Callable[[], Flavor],
        *,
        timeout_s: float,
        attempts: int,
    ) -> None:
        self._link = link
        self._state = state
        self._flavor = flavor
        self.timeout_s = timeout_s
        self.attempts = attempts
        self._waiters: list[tuple[str, asyncio.Future[tuple[float, int]]]] = []

    def on_param_value(self, message: Any) -> None:
        """A PARAM_VALUE of the autopilot: the oldest request for that name gets it."""
        name = _name(message.param_id)
        for waiting_for, future in self._waiters:
            if waiting_for == name and not future.done():
                future.set_result((float(message.param_value), int(message.param_type)))
                return

    async def read(self, name: str) -> float:
        """The current value (PARAM_REQUEST_READ)."""
        st, link = self._state, self._link()
        raw, kind = await self._ask(name, lambda: link.mav.param_request_read_encode(
            st.system_id or 0, st.component_id or 0, name.encode(), -1))  # fmt: skip
        return decode_value(self._flavor(), raw, kind)

    async def write(self, name: str, value: float, param_type: int) -> float:
        """PARAM_SET; the value the autopilot answers with."""
        st, link, flavor = self._state, self._link(), self._flavor()
        encoded = encode_value(flavor, value, param_type)

        def build() -> Any:
            target = (st.system_id or 0, st.component_id or 0)
            return link.mav.param_set_encode(*target, name.encode(), encoded, param_type)

        raw, kind = await self._ask(name, build)
        return decode_value(flavor, raw, kind)

    async def ensure(self, spec: ParamSpec) -> float:
        """Set ``spec`` and read it back; raises :class:`ParamError` unless it holds. A spec
        ``at_most`` or ``needs_reboot`` is read first and left as it is where it already holds."""
        want = spec.value
        if spec.at_most or spec.needs_reboot:
            current = await self.read(spec.name)
            if same_value(current, want) or (spec.at_most and current < want):
                return current
            if spec.needs_reboot:
                await self.write(spec.name, want, spec.param_type)
                raise ParamError(
                    f"parameter {spec.name} ({spec.why}) was {current:g}; set to {want:g}, it "
                    "takes effect only after the autopilot reboots"
                )
        read_back = math.nan
        for _ in range(self.attempts):
            await self.write(spec.name, want, spec.param_type)
            read_back = await self.read(spec.name)
            if same_value(read_back, want):
                return read_back
            # A PARAM_VALUE sent before the set may come after it and answer for it (a
            # parameter list being streamed, a late answer to an earlier try): PX4 SITL under
            # load read MPC_XY_VEL_I_ACC back as its old 0.4 once, and the vehicle was refused
            # for good. The value that holds is the one read back after a set, tried again.
        raise ParamError(
            f"parameter {spec.name} ({spec.why}) is {read_back:g} after setting it to {want:g} "
            f"{self.attempts} times"
        )

    async def _ask(self, name: str, build: Callable[[], Any]) -> tuple[float, int]:
        loop = asyncio.get_running_loop()
        for _ in range(self.attempts):
            future: asyncio.Future[tuple[float, int]] = loop.create_future()
            entry = (name, future)
            self._waiters.append(entry)
            self._link().send(build())
            try:
                return await asyncio.wait_for(future, self.timeout_s)
            except TimeoutError:
                continue
            finally:
                with contextlib.suppress(ValueError):
                    self._waiters.remove(entry)
        raise ParamError(
            f"parameter {name}: no PARAM_VALUE after {self.attempts} tries (unknown to this "
            "autopilot?)"
        )

    def cancel_all(self) -> None:
        for _, future in self._waiters:
            future.cancel()
        self._waiters.clear()


def _name(raw: Any) -> str:
    text = raw.decode(errors="replace") if isinstance(raw, bytes) else str(raw)
    return text.rstrip("\x00")
