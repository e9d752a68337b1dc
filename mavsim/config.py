"""Configuration of one simulated MAVLink vehicle: typed, frozen, validated once."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

from mavsim.errors import MavsimError

Vec3 = tuple[float, float, float]


def _pid(wn_radps: float, zeta: float, ki_radps: float, eps: float) -> tuple[float, float, float]:
    """(kp, kd, ki) placing the poles at the roots of (s + k_i)(s^2 + 2 zeta w_n s + w_n^2),
    divided by eps (the RPT pole pattern of Phang 2015 eq. 9)."""
    kp = (wn_radps**2 + 2 * zeta * wn_radps * ki_radps) / eps**2
    kd = (2 * zeta * wn_radps + ki_radps) / eps
    return kp, kd, ki_radps * wn_radps**2 / eps**3


def _cascade(pos_p: float, vel_p: float, vel_i: float) -> tuple[float, float, float, float]:
    """(kp, kd, ki, kvi) of a P position loop feeding a PI velocity loop with feed-forward:
    ``vel_p (v_ff + pos_p e - v) + vel_i integral(v_ff + pos_p e - v)``."""
    return vel_p * pos_p, vel_p, vel_i * pos_p, vel_i


STIFF_EPS = 0.3
"""Time scale of the stiff indoor tune (:meth:`PositionGains.from_poles`): the paper's poles
1/0.3 times faster (x, y about 5.9 rad/s, z about 7 rad/s), well inside the 25 rad/s inner loop."""


@dataclass(frozen=True)
class PositionGains:
    """Per-axis PID with feed-forward of the autopilot's position controller.

    ``a_cmd = a_ref + kp e + kd e_v + ki integral(e) + kvi integral(e_v)`` with ``e = p_ref - p``
    and ``e_v = v_ref - v``: the paper's PID (``kvi`` 0) or an autopilot's P-position, PI-velocity
    cascade exactly (:meth:`ardupilot`, the default, and :meth:`px4`); :meth:`from_poles` gives
    the paper's pole pattern.
    """

    kp_xy: float = 2.0
    """Position gain in [1/s^2] on the horizontal axes (PSC_POSXY_P x PSC_VELXY_P)."""
    kd_xy: float = 2.0
    """Velocity gain in [1/s] on the horizontal axes (PSC_VELXY_P)."""
    ki_xy: float = 1.0
    """Position-error integral gain in [1/s^3] on the horizontal axes."""
    kvi_xy: float = 1.0
    """Velocity-error integral gain in [1/s^2] on the horizontal axes (PSC_VELXY_I)."""
    kp_z: float = 5.0
    """Position gain in [1/s^2] on the vertical axis (PSC_POSZ_P x PSC_VELZ_P)."""
    kd_z: float = 5.0
    """Velocity gain in [1/s] on the vertical axis (PSC_VELZ_P)."""
    ki_z: float = 2.0
    """Position-error integral gain in [1/s^3] on the vertical axis."""
    kvi_z: float = 2.0
    """Velocity-error integral gain in [1/s^2] on the vertical axis: ArduCopter has none there,
    its acceleration loop's integrator (hover throttle) does that work; 2 stands in for it."""
    integral_limit_m_s: float = 0.5
    """Anti-windup bound of each integral in [m s] (position) and [m] (velocity)."""

    @classmethod
    def ardupilot(
        cls, posxy_p: float = 1.0, velxy_p: float = 2.0, velxy_i: float = 1.0
    ) -> PositionGains:
        """ArduCopter 4.7's (AC_PosControl, multicopter): PSC_POSXY_P, PSC_VELXY_P and
        PSC_VELXY_I as given (their defaults by default), the vertical ones its defaults."""
        (kp, kd, ki, kvi) = _cascade(posxy_p, velxy_p, velxy_i)
        (kpz, kdz, kiz, kviz) = _cascade(1.0, 5.0, 2.0)
        return cls(kp, kd, ki, kvi, kpz, kdz, kiz, kviz)

    @classmethod
    def px4(
        cls,
        xy_p: float = 0.95,
        xy_vel_p: float = 1.8,
        xy_vel_i: float = 0.4,
        z_p: float = 1.0,
        z_vel_p: float = 4.0,
    ) -> PositionGains:
        """PX4 v1.16's: MPC_XY_P, MPC_XY_VEL_P_ACC, MPC_XY_VEL_I_ACC, MPC_Z_P and
        MPC_Z_VEL_P_ACC as given (their defaults 0.95, 1.8, 0.4, 1 and 4 by default);
        MPC_Z_VEL_I_ACC 2."""
        (kp, kd, ki, kvi), (kpz, kdz, kiz, kviz) = (
            _cascade(xy_p, xy_vel_p, xy_vel_i),
            _cascade(z_p, z_vel_p, 2.0),
        )
        return cls(kp, kd, ki, kvi, kpz, kdz, kiz, kviz)

    @classmethod
    def from_poles(cls, eps: float) -> PositionGains:
        """The paper's pole pattern (x, y: w_n 1.772, zeta 0.5, k_i 0.2; z: w_n 2.089,
        zeta 0.66, k_i 0.23) at time scale ``eps`` (1: the paper's own gains)."""
        (kp, kd, ki), (kpz, kdz, kiz) = _pid(1.772, 0.5, 0.2, eps), _pid(2.089, 0.66, 0.23, eps)
        return cls(kp, kd, ki, 0.0, kpz, kdz, kiz, 0.0)


@dataclass(frozen=True)
class VehicleConfig:
    """One simulated vehicle, exposed as a MAVLink endpoint answering like an ArduCopter."""

    vehicle_id: str
    """Show-file vehicle id (for messages and logs)."""
    system_id: int
    """MAVLink system id of the vehicle (1..254); component id is 1 (autopilot)."""
    port: int
    """UDP port the vehicle listens on; it answers every peer that sent it a packet."""
    host: str = "127.0.0.1"
    """Address to bind."""
    autopilot: Literal["ardupilot", "px4"] = "ardupilot"
    """Which autopilot it answers like (modes, OFFBOARD rules; see mavsim/px4.py)."""
    home_m_enu: Vec3 = (0.0, 0.0, 0.0)
    """Start position in the show frame [m]; also the origin of its LOCAL_NED frame."""
    boot_home_offset_m: Vec3 = (0.0, 0.0, 0.0)
    """Where the autopilot's home (its fence's centre, where it returns) lies at boot from the
    start position, in [m] ENU: PX4 SIH takes its home from its GPS at boot, 3.9-4.0 m from
    where EKF2 puts the vehicle once a companion moves its origin (issue 31);
    MAV_CMD_DO_SET_HOME moves it."""
    mass_kg: float = 1.0
    """Vehicle mass in [kg]."""
    thrust_max_n: float = 19.6
    """Largest total thrust in [N]; SET_ATTITUDE_TARGET thrust 1.0 means this."""
    tilt_max_rad: float = math.radians(30.0)
    """Largest commanded tilt (ArduPilot ANGLE_MAX)."""
    position_source_delay_s: float = 3.0
    """Seconds after start before the estimator has a position source; arming is refused before."""
    arm_refusal: str | None = None
    """When set, a pre-arm check fails from boot, in these words after the autopilot's prefix
    (``PreArm: ``, ``Preflight Fail: ``): arming is refused (tests, rehearsal); the autopilot's
    ``prearm_fault`` clears it or sets another while it runs."""
    guided_timeout_s: float | None = None
    """The setpoint timeout at boot in [s] (ArduPilot GUID_TIMEOUT, PX4 COM_OF_LOSS_T); None:
    the autopilot's default (3 s, 1 s)."""
    takeoff_speed_mps: float = 0.5
    """Climb rate of MAV_CMD_NAV_TAKEOFF in [m/s]."""
    land_speed_mps: float = 0.5
    """Descent rate in LAND in [m/s] (ArduPilot LAND_SPEED)."""
    disarm_delay_s: float = 10.0
    """Armed on the ground for this long without taking off -> auto-disarm (DISARM_DELAY)."""
    telemetry_rate_hz: float = 50.0
    """Default rate of LOCAL_POSITION_NED, ATTITUDE and POSITION_TARGET_LOCAL_NED."""
    physics_rate_hz: float = 100.0
    """Rate of the autopilot loop in [Hz] (the simulator's control rate; 4 physics substeps)."""
    gains: PositionGains | None = None
    """Position controller gains; None: the autopilot's own defaults (:attr:`position_gains`)."""
    params: tuple[tuple[str, float], ...] = ()
    """Parameter values at boot besides the defaults (mavsim.params), e.g. ``(("GUID_OPTIONS",
    1),)``."""
    frozen_params: tuple[str, ...] = ()
    """Parameters that refuse every PARAM_SET (answered with the value kept): a misconfigured or
    locked vehicle, for tests and rehearsals."""

    @property
    def position_gains(self) -> PositionGains:
        """The gains flown: ``gains``, or ArduCopter's or PX4's defaults."""
        if self.gains is not None:
            return self.gains
        return PositionGains.px4() if self.autopilot == "px4" else PositionGains.ardupilot()

    def __post_init__(self) -> None:
        if not 1 <= self.system_id <= 254:
            raise MavsimError(f"{self.vehicle_id}: system_id {self.system_id} not in 1..254")
        if not 0 <= self.port <= 65535:
            raise MavsimError(f"{self.vehicle_id}: port {self.port} not in 0..65535")
        positive = {
            "mass_kg": self.mass_kg,
            "thrust_max_n": self.thrust_max_n,
            "guided_timeout_s": 1.0 if self.guided_timeout_s is None else self.guided_timeout_s,
            "takeoff_speed_mps": self.takeoff_speed_mps,
            "land_speed_mps": self.land_speed_mps,
            "telemetry_rate_hz": self.telemetry_rate_hz,
            "physics_rate_hz": self.physics_rate_hz,
        }
        for name, value in positive.items():
            if not value > 0:
                raise MavsimError(f"{self.vehicle_id}: {name} must be > 0, got {value}")
        if self.thrust_max_n <= self.mass_kg * 9.81:
            raise MavsimError(f"{self.vehicle_id}: thrust_max_n cannot lift mass_kg")
        if self.position_source_delay_s < 0:
            raise MavsimError(f"{self.vehicle_id}: position_source_delay_s must be >= 0")
