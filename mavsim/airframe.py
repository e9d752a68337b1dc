"""One simulated airframe: the simulator's quadrotor dynamics plus the ground it stands on.

The physics are ``vehicles.quadrotor_brush.dynamics`` (translational dynamics, 25 rad/s inner
attitude loop, motor lag, drag, ground effect) for a single vehicle; this module adds what an
autopilot needs around them: resting on the ground at the start height, and scalar access to the
state.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mavsim.config import VehicleConfig
from vehicles.quadrotor_brush.dynamics import (
    InnerLoopCommand,
    QuadrotorDynamics,
    QuadrotorState,
    ground_effect_gain,
)
from vehicles.quadrotor_brush.params import QuadrotorParams

Vec3 = tuple[float, float, float]
PHYSICS_SUBSTEPS = 4
"""Physics steps per autopilot loop period."""


@dataclass(frozen=True)
class AttitudeThrust:
    """What the autopilot's position controller asks of the inner loop for one period."""

    roll_rad: float
    """Roll command (body FLU in world ENU, Z-Y-X Euler) in [rad]."""
    pitch_rad: float
    """Pitch command in [rad]."""
    yaw_rad: float
    """Heading command about world z (ENU, from east, counter-clockwise) in [rad]."""
    thrust_mps2: float
    """Collective thrust per unit mass in [m/s^2]; 0 with the motors off."""


class Airframe:
    """A quadrotor that starts at rest on the ground at ``config.home_m_enu``."""

    def __init__(self, config: VehicleConfig) -> None:
        self.params = QuadrotorParams(
            mass_kg=config.mass_kg,
            thrust_to_weight=config.thrust_max_n / (config.mass_kg * 9.81),
            max_tilt_rad=config.tilt_max_rad,
        )
        self.dt_s = 1.0 / config.physics_rate_hz
        self._dynamics = QuadrotorDynamics(
            self.params, self.dt_s / PHYSICS_SUBSTEPS, PHYSICS_SUBSTEPS
        )
        self.ground_z_m = float(config.home_m_enu[2])
        self._state = QuadrotorState(
            position_m_enu=np.array([config.home_m_enu], dtype=np.float64),
            velocity_mps_enu=np.zeros((1, 3)),
            attitude_rad=np.zeros((1, 3)),
            attitude_rate_radps=np.zeros((1, 3)),
            thrust_mps2=np.zeros(1),
            body_z_enu=np.array([[0.0, 0.0, 1.0]]),
        )
        self._no_wind = np.zeros((1, 3))
        self.on_ground = True

    @property
    def gravity_mps2(self) -> float:
        """Gravitational acceleration in [m/s^2]."""
        return self.params.gravity_mps2

    @property
    def max_thrust_mps2(self) -> float:
        """Largest collective thrust per unit mass in [m/s^2]."""
        return self.params.max_specific_thrust_mps2

    @property
    def position_m_enu(self) -> Vec3:
        """Position of the reference point in [m], ENU."""
        p = self._state.position_m_enu[0]
        return (float(p[0]), float(p[1]), float(p[2]))

    @property
    def velocity_mps_enu(self) -> Vec3:
        """Velocity in [m/s], ENU."""
        v = self._state.velocity_mps_enu[0]
        return (float(v[0]), float(v[1]), float(v[2]))

    @property
    def attitude_rad(self) -> Vec3:
        """Roll, pitch, yaw in [rad] (FLU in ENU)."""
        a = self._state.attitude_rad[0]
        return (float(a[0]), float(a[1]), float(a[2]))

    @property
    def attitude_rate_radps(self) -> Vec3:
        """Euler angle rates in [rad/s]."""
        r = self._state.attitude_rate_radps[0]
        return (float(r[0]), float(r[1]), float(r[2]))

    @property
    def rotor_thrust_n(self) -> float:
        """Collective thrust of the rotors now in [N] (0 with the motors off)."""
        return float(self._state.thrust_mps2[0]) * self.params.mass_kg

    def step(self, command: AttitudeThrust) -> None:
        """Advance one autopilot period under ``command``."""
        state = self._state
        height = state.position_m_enu[:, 2] - self.ground_z_m
        gain = ground_effect_gain(height, self.params.rotor_radius_m)
        self._dynamics.advance(
            state,
            InnerLoopCommand(
                throttle=np.array([command.thrust_mps2 * self.params.throttle_per_mps2]),
                roll_rad=np.array([command.roll_rad]),
                pitch_rad=np.array([command.pitch_rad]),
                yaw_rad=np.array([command.yaw_rad]),
            ),
            self._no_wind,
            gain,
        )
        self._contact_ground()

    def _contact_ground(self) -> None:
        """The ground carries the vehicle: no sinking, no sliding while resting on it."""
        p = self._state.position_m_enu
        v = self._state.velocity_mps_enu
        if p[0, 2] <= self.ground_z_m and v[0, 2] <= 0.0:
            p[0, 2] = self.ground_z_m
            v[0, :] = 0.0
            self.on_ground = True
        elif p[0, 2] > self.ground_z_m + 1e-3:
            self.on_ground = False
