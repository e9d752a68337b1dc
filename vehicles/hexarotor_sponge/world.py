"""The simulated world in MuJoCo: the hexarotor, its arm and F/T sensor, the sponge pen on a
spring, a vertical wall with Coulomb friction, wind, and a motion-capture system with noise and
latency. The MJCF is built here in code; contact and friction are MuJoCo's, not a hand-written law.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import mujoco
import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.allocation import rotor_geometry
from vehicles.hexarotor_sponge.fly_settings import WorldNoise
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.rotations import rotation_of
from vehicles.surface import Surface

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Measurement:
    """What the controller sees at one tick."""

    base_m_enu: FloatArray
    """(3,) measured body position in [m] (mocap, delayed and noisy)."""
    velocity_mps_enu: FloatArray
    """(3,) measured body velocity in [m/s]."""
    rotation_body_to_enu: FloatArray
    """(3, 3) measured attitude."""
    omega_radps_body: FloatArray
    """(3,) body rates in [rad/s] (gyro, body frame)."""
    ft_force_n_sensor: FloatArray
    """(3,) F/T force in [N], sensor (= body) axes: what the arm pushes on the body."""
    ft_torque_nm_sensor: FloatArray
    """(3,) F/T torque in [N m] about the sensor, sensor axes."""


@dataclass(frozen=True)
class Truth:
    """True state for logs and metrics."""

    base_m_enu: FloatArray
    """(3,) body centre in [m]."""
    tip_m_enu: FloatArray
    """(3,) sponge tip in [m]."""
    contact_force_n: float
    """Normal force in [N] between pen and wall over the last control period (mean of the
    physics steps; 0 without contact)."""
    attitude_wxyz_enu: FloatArray
    """(4,) body attitude, MuJoCo's quaternion (w, x, y, z): body FLU -> world ENU."""


def facing_rotation(surface: Surface) -> FloatArray:
    """Body attitude (3, 3) with the arm (body x) pointing into the wall and body z up."""
    x = -surface.normal_enu
    z = np.array([0.0, 0.0, 1.0])
    return np.asarray(np.column_stack([x, np.cross(z, x), z]))


def _cone_vertices(length_m: float, radius_m: float) -> str:
    """Apex at the origin pointing +x, base circle ``length_m`` behind it."""
    pts = [(0.0, 0.0, 0.0)]
    for k in range(12):
        a = 2.0 * math.pi * k / 12
        pts.append((-length_m, radius_m * math.cos(a), radius_m * math.sin(a)))
    return " ".join(f"{x:.5f} {y:.5f} {z:.5f}" for x, y, z in pts)


def _vec(v: FloatArray | tuple[float, ...]) -> str:
    return " ".join(f"{float(c):.6g}" for c in v)


def build_mjcf(params: HexarotorParams, surface: Surface, dt_s: float) -> str:
    """The world as MJCF text (wall through ``surface``, vehicle at the origin)."""
    geo = rotor_geometry(params)
    mu = params.wall_friction
    ixx, iyy, izz = params.base_inertia_kgm2
    length = params.arm_length_m
    rotors = "\n".join(
        f'<site name="rotor{i}" pos="{_vec(geo.position_m_body[i])}" '
        f'zaxis="{_vec(geo.axis_body[i])}" size="0.02"/>'
        for i in range(6)
    )
    actuators = "\n".join(
        f'<general site="rotor{i}" gear="0 0 1 0 0 {params.drag_torque_m * geo.spin[i]:.6g}" '
        f'ctrllimited="true" ctrlrange="0 {params.thrust_max_n}"/>'
        for i in range(6)
    )
    springref = -params.pen_preload_n / params.pen_stiffness_npm
    return f"""
<mujoco model="hexarotor_sponge">
  <option timestep="{dt_s}" gravity="0 0 {-GRAVITY_MPS2}" integrator="implicitfast"
          cone="elliptic"/>
  <asset><mesh name="cone" vertex="{_cone_vertices(0.05, 0.015)}"/></asset>
  <worldbody>
    <geom name="wall" type="plane" pos="{_vec(surface.origin_m_enu)}"
          zaxis="{_vec(surface.normal_enu)}" size="3 3 0.01" contype="1" conaffinity="2"
          friction="{mu} 0.005 0.0001"/>
    <body name="base">
      <freejoint/>
      <inertial pos="0 0 0" mass="{params.base_mass_kg}" diaginertia="{ixx} {iyy} {izz}"/>
      <geom type="cylinder" size="{params.rotor_radius_m} 0.03" contype="0" conaffinity="0"
            mass="0"/>
      {rotors}
      <body name="arm" pos="{_vec(params.arm_base_m_body)}">
        <inertial pos="{length / 2} 0 0" mass="{params.arm_mass_kg}"
                  diaginertia="1e-4 {params.arm_mass_kg * length**2 / 12} \
{params.arm_mass_kg * length**2 / 12}"/>
        <site name="ft" pos="0 0 0" size="0.02"/>
        <geom type="capsule" fromto="0 0 0 {length - 0.05} 0 0" size="0.008" contype="0"
              conaffinity="0" mass="0"/>
        <body name="pen" pos="{length} 0 0">
          <joint name="pen_slide" type="slide" axis="-1 0 0" limited="true"
                 range="0 {params.pen_travel_m}" stiffness="{params.pen_stiffness_npm}"
                 springref="{springref}" damping="{params.pen_damping_nspm}"/>
          <inertial pos="-0.02 0 0" mass="{params.pen_mass_kg}" diaginertia="1e-5 1e-5 1e-5"/>
          <geom name="sponge" type="mesh" mesh="cone" contype="2" conaffinity="1"
                friction="{mu} 0.005 0.0001" mass="0"
                solimp="{params.sponge_impedance_touch} 0.95 0.001"/>
        </body>
      </body>
    </body>
  </worldbody>
  <actuator>{actuators}</actuator>
  <sensor><force site="ft"/><torque site="ft"/></sensor>
</mujoco>
"""


class WallWorld:
    """One hexarotor in front of one wall, stepped one control period at a time."""

    def __init__(
        self,
        params: HexarotorParams,
        surface: Surface,
        *,
        base_m_enu: FloatArray,
        noise: WorldNoise,
        seed: int = 0,
        physics_dt_s: float = 0.002,
        control_dt_s: float = 0.01,
    ) -> None:
        self.params = params
        self.surface = surface
        self.noise = noise
        self.model = mujoco.MjModel.from_xml_string(build_mjcf(params, surface, physics_dt_s))
        self.data = mujoco.MjData(self.model)
        self.substeps = max(1, round(control_dt_s / physics_dt_s))
        self.control_dt_s = self.substeps * physics_dt_s
        self._rng = np.random.default_rng(seed)
        self._gust = np.zeros(3)
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, facing_rotation(surface).reshape(-1))
        self.data.qpos[0:3] = base_m_enu
        self.data.qpos[3:7] = quat
        mujoco.mj_forward(self.model, self.data)
        self._base_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "base")
        self._pen_id = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_BODY, "pen")
        self._wall_geom = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "wall")
        self._sponge_geom = mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_GEOM, "sponge")
        lag = max(0, round(noise.mocap_latency_s / self.control_dt_s))
        self._delayed: deque[tuple[FloatArray, FloatArray, FloatArray]] = deque(maxlen=lag + 1)
        self._delayed.append(self._pose_now())
        self._mean_force_n = 0.0

    @property
    def time_s(self) -> float:
        """Simulated time in [s]."""
        return float(self.data.time)

    def step(self, thrust_n: FloatArray) -> None:
        """Hold rotor thrusts in [N] for one control period."""
        self.data.ctrl[:] = thrust_n
        self._update_wind()
        force = 0.0
        for _ in range(self.substeps):
            mujoco.mj_step(self.model, self.data)
            force += self._contact_force_n()
        self._mean_force_n = force / self.substeps
        self._delayed.append(self._pose_now())

    def _update_wind(self) -> None:
        n = self.noise
        theta = self.control_dt_s / 1.0
        self._gust += -theta * self._gust + n.gust_mps * math.sqrt(2.0 * theta) * (
            self._rng.standard_normal(3)
        )
        wind = n.wind_mps * np.asarray(self.surface.x_axis_enu) + self._gust
        rel = wind - self.data.qvel[0:3]
        self.data.xfrc_applied[self._base_id, 0:3] = (
            0.5 * 1.225 * n.drag_area_m2 * np.linalg.norm(rel) * rel
        )

    def _pose_now(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        rot = self.data.xmat[self._base_id].reshape(3, 3).copy()
        return self.data.qpos[0:3].copy(), self.data.qvel[0:3].copy(), rot

    def measure(self) -> Measurement:
        """Sensor readings at the current time (mocap from ``mocap_latency_s`` ago)."""
        n, rng = self.noise, self._rng
        pos, vel, rot = self._delayed[0]
        tilt = n.mocap_attitude_rad * rng.standard_normal(3)
        noisy_rot = rot @ rotation_of(tilt)
        sensor = self.data.sensordata
        return Measurement(
            base_m_enu=pos + n.mocap_position_m * rng.standard_normal(3),
            velocity_mps_enu=vel + n.mocap_velocity_mps * rng.standard_normal(3),
            rotation_body_to_enu=noisy_rot,
            omega_radps_body=self.data.qvel[3:6].copy(),
            ft_force_n_sensor=-sensor[0:3] + n.ft_force_n * rng.standard_normal(3),
            ft_torque_nm_sensor=-sensor[3:6] + n.ft_torque_nm * rng.standard_normal(3),
        )

    def truth(self) -> Truth:
        """True base, tip and contact force."""
        return Truth(
            base_m_enu=self.data.xpos[self._base_id].copy(),
            tip_m_enu=self.data.xpos[self._pen_id].copy(),
            contact_force_n=self._mean_force_n,
            attitude_wxyz_enu=self.data.xquat[self._base_id].copy(),
        )

    def _contact_force_n(self) -> float:
        total = 0.0
        frame = np.zeros(6)
        pair = {self._wall_geom, self._sponge_geom}
        for i in range(self.data.ncon):
            c = self.data.contact[i]
            if {int(c.geom1), int(c.geom2)} == pair:
                mujoco.mj_contactForce(self.model, self.data, i, frame)
                total += float(frame[0])
        return total
