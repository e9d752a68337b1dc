"""The parameters a simulated autopilot knows, answered over the MAVLink parameter protocol.

Only parameters whose behaviour the simulator reproduces are listed, with the real autopilots'
names, types and defaults; any other name is unknown (no PARAM_VALUE comes back, as ArduPilot and
PX4 do for a name they do not have). ArduPilot carries every value as a float; PX4 packs integer
parameters bytewise into the float field (MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE).

ArduCopter: GUID_TIMEOUT [s] (stop following when setpoints stop), WP_YAW_BEHAVIOR (0: never turn
the vehicle on its own; otherwise face the direction of travel when a setpoint ignores yaw),
GUID_OPTIONS (bit 3: SET_ATTITUDE_TARGET thrust is thrust, otherwise a climb rate),
WPNAV_SPEED_UP/WPNAV_SPEED_DN [cm/s] (that climb rate's scale, and the shaped path's vertical
speeds), WPNAV_SPEED [cm/s], WPNAV_ACCEL and WPNAV_ACCEL_Z [cm/s^2], PSC_JERK_XY and PSC_JERK_Z
[m/s^3] (the guided target's shaped path, :mod:`mavsim.shaping`), TKOFF_SLEW_TIME [s] (the
take-off's throttle ramp), PSC_POSXY_P [1/s], PSC_VELXY_P [1/s] and PSC_VELXY_I [1/s^2] (the
horizontal P-PI cascade), FENCE_ENABLE, FENCE_TYPE (bit 0
maximum altitude, bit 1 circle), FENCE_RADIUS [m], FENCE_ALT_MAX [m], FENCE_ACTION (0 report,
2 land, others: RTL). PX4: COM_OF_LOSS_T [s], COM_OBL_RC_ACT (what flies when the
offboard stream is lost, :mod:`mavsim.px4`), GF_MAX_HOR_DIST [m], GF_MAX_VER_DIST [m] (0: off),
GF_ACTION (0 none, 1 warning, 2 hold, 3 return, 5 land), MPC_XY_P [1/s], MPC_XY_VEL_P_ACC [1/s]
and MPC_XY_VEL_I_ACC [1/s^2] (the horizontal P-PI cascade), MPC_Z_P [1/s] and MPC_Z_VEL_P_ACC
[1/s] (the vertical one).

Motion-capture fusion (:mod:`mavsim.mocap`): ArduCopter VISO_TYPE (read at boot) and
EK3_SRC1_POSXY decide whether mocap is the position source; PX4 EKF2_EV_CTRL and EKF2_GPS_CTRL.
The other estimator parameters a companion sets with them (EK3_SRC1_POSZ/VELXY/VELZ,
VISO_POS_M_NSE, VISO_DELAY_MS, EK3_TAU_OUTPUT; EKF2_HGT_REF, EKF2_EVP_NOISE, EKF2_EVV_NOISE,
EKF2_EVV_GATE, EKF2_ACC_NOISE, EKF2_TAU_POS/VEL,
EKF2_RNG_CTRL, EKF2_ASP_DELAY, EKF2_DELAY_MAX) are kept and read back with the real defaults; the
simulated estimator is exact, so they change nothing else.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from typing import Literal

from mavsim.errors import MavsimError

INT8, INT16, INT32, REAL32 = 2, 4, 6, 9
"""MAV_PARAM_TYPE of the parameters below."""
_INTEGER_TYPES = frozenset(range(1, 9))

Flavor = Literal["ardupilot", "px4"]


@dataclass(frozen=True)
class ParamDef:
    """A parameter's name, MAV_PARAM_TYPE and default."""

    name: str
    param_type: int
    default: float


ARDUPILOT_PARAMS = (
    ParamDef("GUID_TIMEOUT", REAL32, 3.0),
    ParamDef("WP_YAW_BEHAVIOR", INT8, 2),
    ParamDef("GUID_OPTIONS", INT32, 0),
    ParamDef("WPNAV_SPEED_UP", REAL32, 250.0),
    ParamDef("WPNAV_SPEED_DN", REAL32, 150.0),
    ParamDef("WPNAV_SPEED", REAL32, 1000.0),
    ParamDef("WPNAV_ACCEL", REAL32, 250.0),
    ParamDef("WPNAV_ACCEL_Z", REAL32, 100.0),
    ParamDef("PSC_JERK_XY", REAL32, 5.0),
    ParamDef("PSC_JERK_Z", REAL32, 5.0),
    ParamDef("PSC_POSXY_P", REAL32, 1.0),
    ParamDef("PSC_VELXY_P", REAL32, 2.0),
    ParamDef("PSC_VELXY_I", REAL32, 1.0),
    ParamDef("TKOFF_SLEW_TIME", REAL32, 2.0),
    ParamDef("FENCE_ENABLE", INT8, 0),
    ParamDef("FENCE_TYPE", INT8, 7),
    ParamDef("FENCE_RADIUS", REAL32, 300.0),
    ParamDef("FENCE_ALT_MAX", REAL32, 100.0),
    ParamDef("FENCE_ACTION", INT8, 1),
    ParamDef("VISO_TYPE", INT8, 0),
    ParamDef("EK3_SRC1_POSXY", INT8, 3),
    ParamDef("EK3_SRC1_POSZ", INT8, 1),
    ParamDef("EK3_SRC1_VELXY", INT8, 3),
    ParamDef("EK3_SRC1_VELZ", INT8, 3),
    ParamDef("VISO_POS_M_NSE", REAL32, 0.2),
    ParamDef("VISO_DELAY_MS", INT16, 10),
    ParamDef("EK3_TAU_OUTPUT", INT8, 25),
)
PX4_PARAMS = (
    ParamDef("COM_OF_LOSS_T", REAL32, 1.0),
    ParamDef("COM_OBL_RC_ACT", INT32, 0),
    ParamDef("GF_MAX_HOR_DIST", REAL32, 0.0),
    ParamDef("GF_MAX_VER_DIST", REAL32, 0.0),
    ParamDef("GF_ACTION", INT32, 2),
    ParamDef("MPC_XY_P", REAL32, 0.95),
    ParamDef("MPC_XY_VEL_P_ACC", REAL32, 1.8),
    ParamDef("MPC_XY_VEL_I_ACC", REAL32, 0.4),
    ParamDef("MPC_Z_P", REAL32, 1.0),
    ParamDef("MPC_Z_VEL_P_ACC", REAL32, 4.0),
    ParamDef("EKF2_EV_CTRL", INT32, 0),
    ParamDef("EKF2_HGT_REF", INT32, 1),
    ParamDef("EKF2_GPS_CTRL", INT32, 7),
    ParamDef("EKF2_EVP_NOISE", REAL32, 0.1),
    ParamDef("EKF2_EVV_NOISE", REAL32, 0.1),
    ParamDef("EKF2_EVV_GATE", REAL32, 3.0),
    ParamDef("EKF2_ACC_NOISE", REAL32, 0.35),
    ParamDef("EKF2_TAU_POS", REAL32, 0.25),
    ParamDef("EKF2_TAU_VEL", REAL32, 0.25),
    ParamDef("EKF2_RNG_CTRL", INT32, 1),
    ParamDef("EKF2_ASP_DELAY", REAL32, 100.0),
    ParamDef("EKF2_DELAY_MAX", REAL32, 200.0),
)


class ParamTable:
    """One autopilot's parameters: typed values, set and read over MAVLink."""

    def __init__(
        self,
        flavor: Flavor,
        overrides: dict[str, float] | None = None,
        *,
        frozen: tuple[str, ...] = (),
    ) -> None:
        self.flavor = flavor
        defs = PX4_PARAMS if flavor == "px4" else ARDUPILOT_PARAMS
        self.defs = {d.name: d for d in defs}
        self._values = {d.name: float(d.default) for d in defs}
        for name, value in (overrides or {}).items():
            self.set(name, value)
        unknown = sorted(set(frozen) - set(self.defs))
        if unknown:
            raise MavsimError(f"frozen parameters unknown to {flavor}: {unknown}")
        self.frozen = frozenset(frozen)
        """Names whose PARAM_SET is refused (:meth:`set_from_link` keeps the value)."""

    def __contains__(self, name: str) -> bool:
        return name in self.defs

    def __getitem__(self, name: str) -> float:
        return self._values[name]

    @property
    def names(self) -> list[str]:
        """Parameter names in their index order."""
        return list(self.defs)

    def set(self, name: str, value: float) -> float:
        """Store a value (integers rounded, as the autopilot's storage does); the value kept."""
        if name not in self.defs:
            raise MavsimError(f"unknown parameter {name!r}; known: {', '.join(self.defs)}")
        kind = self.defs[name].param_type
        kept = float(round(value)) if kind in _INTEGER_TYPES else float(value)
        self._values[name] = kept
        return kept

    def set_from_link(self, name: str, raw: float) -> float:
        """A PARAM_SET: store the decoded value unless the parameter is frozen; the value kept."""
        if name in self.frozen:
            return self._values[name]
        return self.set(name, self.decode(name, raw))

    def encode(self, name: str) -> tuple[float, int]:
        """(param_value, param_type) of a PARAM_VALUE for ``name``."""
        kind = self.defs[name].param_type
        value = self._values[name]
        if self.flavor == "px4" and kind in _INTEGER_TYPES:
            return struct.unpack("<f", struct.pack("<i", int(value)))[0], kind
        return value, kind

    def decode(self, name: str, raw: float) -> float:
        """The value a PARAM_SET's param_value carries for ``name``."""
        kind = self.defs[name].param_type
        if self.flavor == "px4" and kind in _INTEGER_TYPES:
            return float(struct.unpack("<i", struct.pack("<f", raw))[0])
        return float(raw)
