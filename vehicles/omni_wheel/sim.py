"""One or more ground writers in MuJoCo: torque-limited wheel motors under PID, noisy sensing.

Each control period (``control_dt_s``) the caller gives every wheel a rate reference; inside the
period a PID per wheel runs at the physics rate on the sensed wheel rate (noisy encoder) and its
torque is clipped to the motor's limit. The controller sees only :class:`Sensed` (wheel rates,
free-joint angles from potentiometers and their filtered rates, tilt and gyro of the rear part);
metrics read :class:`TrueState`.

Friction is static or dynamic per roller (Table 1 gives both; MuJoCo has one coefficient): a
roller whose contact slides at the start of a control period grips with the dynamic coefficient
through it, so a slipping wheel loses traction as in the paper's Working Model 2D. It is decided
per control period (24 us a call, 3 % of a period's 0.8 ms), not per physics step (15 %).
"""

from __future__ import annotations

from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from vehicles.omni_wheel.geometry import WHEEL_NAMES, OmniGeometry
from vehicles.omni_wheel.model import build_mjcf, vehicle_prefix
from vehicles.omni_wheel.terrain import Terrain

FloatArray = NDArray[np.float64]

PHYSICS_DT_S = 0.002
"""Physics step in [s] used by the simulation (the MJCF default is overridden)."""
SLIDING_SPEED_MPS = 0.02
"""Speed in [m/s] of a roller's contact point over the ground above which it slides: its friction
is then the dynamic coefficient (MuJoCo has one coefficient; soft contacts creep below this)."""


@dataclass(frozen=True)
class SensorNoise:
    """Standard deviations of the sensors' white noise."""

    wheel_rate_radps: float = 0.05
    """Encoder-derived wheel rate in [rad/s]."""
    joint_angle_rad: float = 0.002
    """Potentiometers of free joint 1 in [rad]."""
    gyro_radps: float = 0.02
    """Rear part's rate gyro in [rad/s]."""
    tilt_rad: float = 0.003
    """Rear part's tilt sensors in [rad]."""


@dataclass(frozen=True)
class WheelPid:
    """PID of one wheel's rate, torque output in [N m]."""

    kp_nm_per_radps: float = 1.5
    """Proportional gain in [N m / (rad/s)]."""
    ki_nm_per_rad: float = 15.0
    """Integral gain in [N m / rad]."""
    integral_limit_rad: float = 0.2
    """Bound in [rad] on the integrated rate error (anti-windup)."""


@dataclass(frozen=True)
class Sensed:
    """What a vehicle's controller measures at one control tick."""

    wheel_rate_radps: FloatArray
    """(7,) motor rates in [rad/s] (wheel relative to its part)."""
    joint_angles_rad: FloatArray
    """(2,) free joint 1: pitch theta_1 and roll gamma_1 in [rad]."""
    joint_rates_radps: FloatArray
    """(2,) their rates in [rad/s], differentiated and low-pass filtered."""
    gyro_radps: FloatArray
    """(3,) angular velocity of the rear part in [rad/s], its own frame."""
    tilt_rad: FloatArray
    """(2,) roll and pitch of the rear part in [rad]."""


@dataclass(frozen=True)
class TrueState:
    """The true state of one vehicle (for metrics)."""

    base_m_enu: FloatArray
    """(3,) middle axle centre in [m], world ENU."""
    base_velocity_mps_enu: FloatArray
    """(3,) its velocity in [m/s]."""
    rotation: FloatArray
    """(3, 3) rear part's orientation (columns: its axes in world ENU)."""
    hub_m_enu: FloatArray
    """(7, 3) wheel centres in [m]."""
    hub_velocity_mps_enu: FloatArray
    """(7, 3) wheel centre velocities in [m/s]."""
    wheel_spin_radps: FloatArray
    """(7,) absolute spin of each wheel about its axle in [rad/s]."""
    motor_rate_radps: FloatArray
    """(7,) true motor rates in [rad/s]."""
    axle_enu: FloatArray
    """(7, 3) wheel axles in world ENU."""
    pen_m_enu: FloatArray
    """(3,) the marker's point (under the front linkage's middle) at floor level, [m]."""
    joint_angles_rad: FloatArray
    """(2,) free joint 1: pitch and roll of the front part relative to the rear part in [rad]."""


class _Vehicle:
    """Indices of one vehicle in the shared model."""

    def __init__(self, model: mujoco.MjModel, k: int) -> None:
        p = vehicle_prefix(k)
        base = model.joint(f"{p}base")
        self.qpos = int(base.qposadr[0])
        self.qvel = int(base.dofadr[0])
        self.rear = int(model.body(f"{p}rear").id)
        self.front = int(model.body(f"{p}front").id)
        self.pen = int(model.site(f"{p}pen").id)
        joints = [model.joint(f"{p}joint1_{n}") for n in ("pitch", "roll")]
        self.joint_qpos = np.array([int(j.qposadr[0]) for j in joints])
        self.joint_dof = np.array([int(j.dofadr[0]) for j in joints])
        wheels = [model.joint(f"{p}{w}") for w in WHEEL_NAMES]
        self.wheel_dof = np.array([int(j.dofadr[0]) for j in wheels])
        self.hubs = np.array([int(model.body(f"{p}{w}").id) for w in WHEEL_NAMES])
        self.wheel_jnt = np.array([int(j.id) for j in wheels])
        self.actuators = np.array([int(model.actuator(f"{p}{w}").id) for w in WHEEL_NAMES])


class OmniWorld:
    """Vehicles on a terrain, advanced one control period per :meth:`step`."""

    def __init__(
        self,
        geometry: OmniGeometry,
        terrain: Terrain,
        starts: tuple[tuple[float, float, float, float], ...],
        *,
        seed: int = 0,
        control_dt_s: float = 0.01,
        noise: SensorNoise = SensorNoise(),
        pid: WheelPid = WheelPid(),
    ) -> None:
        self.geometry, self.terrain = geometry, terrain
        self.model = mujoco.MjModel.from_xml_string(build_mjcf(geometry, terrain, starts))
        self.model.opt.timestep = PHYSICS_DT_S
        self.data = mujoco.MjData(self.model)
        self.vehicles = [_Vehicle(self.model, k) for k in range(len(starts))]
        self.control_dt_s = control_dt_s
        self.substeps = max(1, round(control_dt_s / PHYSICS_DT_S))
        self.noise, self.pid = noise, pid
        self._rng = np.random.default_rng(seed)
        n = len(starts)
        self._integral = np.zeros((n, 7))
        self._joint_prev = np.zeros((n, 2))
        self._joint_rate = np.zeros((n, 2))
        self.enabled = np.ones(n, dtype=bool)
        self._is_roller = self.model.geom_contype == 1  # the only vehicle geoms that collide
        self._rollers = np.flatnonzero(self._is_roller)
        self._friction_static = geometry.friction_static
        self._friction_dynamic = min(geometry.friction_dynamic, geometry.friction_static)
        mujoco.mj_forward(self.model, self.data)
        for k in range(n):
            self._joint_prev[k] = self._pots(k)

    @property
    def t_s(self) -> float:
        """Simulated time in [s]."""
        return float(self.data.time)

    def _pots(self, k: int) -> FloatArray:
        v = self.vehicles[k]
        true = self.data.qpos[v.joint_qpos]
        return np.asarray(true + self._rng.normal(0.0, self.noise.joint_angle_rad, 2))

    def step(self, wheel_refs_radps: FloatArray) -> None:
        """Advance one control period with (n_vehicles, 7) wheel rate references in [rad/s]."""
        refs = np.asarray(wheel_refs_radps, dtype=np.float64).reshape(len(self.vehicles), 7)
        dt, torque_max = PHYSICS_DT_S, self.geometry.motor_torque_max_nm
        self._slide_friction()
        for _ in range(self.substeps):
            for k, v in enumerate(self.vehicles):
                if not self.enabled[k]:
                    self.data.ctrl[v.actuators] = 0.0
                    self._integral[k] = 0.0
                    continue
                rate = self.data.qvel[v.wheel_dof]
                rate = rate + self._rng.normal(0.0, self.noise.wheel_rate_radps, 7)
                err = refs[k] - rate
                lim = self.pid.integral_limit_rad
                self._integral[k] = np.clip(self._integral[k] + err * dt, -lim, lim)
                torque = self.pid.kp_nm_per_radps * err + self.pid.ki_nm_per_rad * self._integral[k]
                self.data.ctrl[v.actuators] = np.clip(torque, -torque_max, torque_max)
            mujoco.mj_step(self.model, self.data)
        for k in range(len(self.vehicles)):
            pots = self._pots(k)
            raw = (pots - self._joint_prev[k]) / self.control_dt_s
            self._joint_rate[k] += 0.25 * (raw - self._joint_rate[k])
            self._joint_prev[k] = pots

    def _slide_friction(self) -> None:
        """Each roller's friction for the next control period: dynamic where one of its contacts
        (of the last physics step) slides faster than :data:`SLIDING_SPEED_MPS` over the (fixed)
        terrain, static elsewhere. A contact's two friction rows of the constraint velocity
        (rows 1 and 2 after its normal row, elliptic cones) are its sliding velocity."""
        m, d = self.model, self.data
        m.geom_friction[self._rollers, 0] = self._friction_static
        if d.ncon == 0 or self._friction_dynamic == self._friction_static:
            return
        contact = d.contact
        row = contact.efc_address
        active = row >= 0
        slide_1, slide_2 = d.efc_vel[row[active] + 1], d.efc_vel[row[active] + 2]
        sliding = slide_1 * slide_1 + slide_2 * slide_2 > SLIDING_SPEED_MPS**2
        pair = contact.geom[active][sliding]
        roller = np.where(self._is_roller[pair[:, 0]], pair[:, 0], pair[:, 1])
        m.geom_friction[roller, 0] = self._friction_dynamic

    def sense(self, k: int) -> Sensed:
        """The sensors of vehicle ``k`` now."""
        v, rng, nz = self.vehicles[k], self._rng, self.noise
        rot = self.data.xmat[v.rear].reshape(3, 3)
        roll = float(np.arctan2(rot[2, 1], rot[2, 2]))
        pitch = float(np.arcsin(np.clip(-rot[2, 0], -1.0, 1.0)))
        gyro = self.data.qvel[v.qvel + 3 : v.qvel + 6]
        return Sensed(
            wheel_rate_radps=self.data.qvel[v.wheel_dof] + rng.normal(0.0, nz.wheel_rate_radps, 7),
            joint_angles_rad=self._joint_prev[k].copy(),
            joint_rates_radps=self._joint_rate[k].copy(),
            gyro_radps=gyro + rng.normal(0.0, nz.gyro_radps, 3),
            tilt_rad=np.array([roll, pitch]) + rng.normal(0.0, nz.tilt_rad, 2),
        )

    def truth(self, k: int) -> TrueState:
        """The true state of vehicle ``k`` now."""
        v, m, d = self.vehicles[k], self.model, self.data
        vel = np.zeros(6)
        hub_vel = np.empty((7, 3))
        spin = np.empty(7)
        axle = np.empty((7, 3))
        for i, (body, jnt) in enumerate(zip(v.hubs, v.wheel_jnt, strict=True)):
            mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, int(body), vel, 0)
            axle[i] = d.xaxis[jnt]
            hub_vel[i] = vel[3:]
            spin[i] = float(vel[:3] @ axle[i])
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, v.rear, vel, 0)
        pen = d.site_xpos[v.pen].copy()
        pen[2] = self.terrain.height_at_m(float(pen[0]))
        return TrueState(
            base_m_enu=d.xpos[v.rear].copy(),
            base_velocity_mps_enu=vel[3:].copy(),
            rotation=d.xmat[v.rear].reshape(3, 3).copy(),
            hub_m_enu=d.xpos[v.hubs].copy(),
            hub_velocity_mps_enu=hub_vel,
            wheel_spin_radps=spin,
            motor_rate_radps=d.qvel[v.wheel_dof].copy(),
            axle_enu=axle,
            pen_m_enu=pen,
            joint_angles_rad=d.qpos[v.joint_qpos].copy(),
        )
