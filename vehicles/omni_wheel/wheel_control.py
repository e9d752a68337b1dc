"""Wheel references from the body configuration (Chugo et al., eq. 1-20), pure functions.

Frames: every vector is expressed in the rear part's frame {4} (see ``geometry``): x forward,
y left, z up. Sign conventions differ from the paper's (its z axis is our -y), so eq. 17's
``+ sigma_z`` reads here ``- Omega_part . axle``: a motor measures its wheel's spin relative to
the part that carries it, so a part pitching nose-up (negative about y) adds to the spin the
motor must give for the same rolling speed.

The standard method gives every x-driving wheel the fixed reference ``V0 / r``. The proposed
method (Fig. 4) sets the reference point's velocity to ``V0`` along x of {4} (eq. 13), derives
each wheel's velocity through the linkage chain (eq. 1, 7-10) from the sensed joint and tilt
rates (eq. 11-12), scales all of them by one factor so that none exceeds ``V0`` (eq. 14-15), and
turns each into a spin reference in the wheel's own frame, whose x axis is tilted by ``alpha``
until the velocity lies along it (eq. 16-18).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicles.omni_wheel.geometry import FRONT_PART, OmniGeometry

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class BodyConfiguration:
    """The sensed configuration of the body (potentiometers on joint 1, tilt sensors)."""

    rear_rate_radps: tuple[float, float, float] = (0.0, 0.0, 0.0)
    """Angular velocity of the rear part in [rad/s] about its x (roll), y (pitch), z (yaw)."""
    joint_pitch_rad: float = 0.0
    """theta_1: pitch of the front part relative to the rear part in [rad] (about y)."""
    joint_roll_rad: float = 0.0
    """gamma_1: roll of the front part relative to the rear part in [rad] (about its x)."""
    joint_pitch_rate_radps: float = 0.0
    """Rate of ``joint_pitch_rad`` in [rad/s]."""
    joint_roll_rate_radps: float = 0.0
    """Rate of ``joint_roll_rad`` in [rad/s]."""


def _rot_x(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(a: float) -> FloatArray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def chain_velocity(
    v_i_mps: FloatArray, sigma_i_radps: FloatArray, p_i_next_m: FloatArray
) -> FloatArray:
    """Eq. (1): velocity in [m/s] of the next wheel from wheel ``i``'s velocity, the rotation
    vector ``sigma_i`` in [rad/s] of the link between them and the position ``p`` in [m] from
    wheel ``i`` to the next wheel (all in one frame)."""
    return np.asarray(v_i_mps + np.cross(sigma_i_radps, p_i_next_m))


@dataclass(frozen=True)
class PartKinematics:
    """Per-wheel quantities of the chain in frame {4}."""

    velocity_mps: FloatArray
    """(7, 3) velocity of each wheel centre in [m/s]."""
    part_rate_radps: FloatArray
    """(7, 3) angular velocity in [rad/s] of the part carrying each wheel."""
    axle: FloatArray
    """(7, 3) unit axle of each wheel (positive spin rolls it along its drive direction)."""
    drive: FloatArray
    """(7, 3) unit drive direction of each wheel."""


def wheel_kinematics(
    velocity_ref_mps: FloatArray, config: BodyConfiguration, geometry: OmniGeometry
) -> PartKinematics:
    """Eq. (7)-(12) for this layout: each wheel's velocity in {4} from the reference point's
    velocity ``velocity_ref_mps`` (3,) in [m/s] (the middle axle's centre) and the body
    configuration; the rear part's wheels through its own rotation, the front part's through joint
    1 and its relative pitch and roll rates."""
    omega_rear = np.asarray(config.rear_rate_radps, dtype=np.float64)
    rel = _rot_y(config.joint_pitch_rad) @ _rot_x(config.joint_roll_rad)
    sigma_front = omega_rear + np.array([0.0, config.joint_pitch_rate_radps, 0.0])
    sigma_front = sigma_front + _rot_y(config.joint_pitch_rad) @ np.array(
        [config.joint_roll_rate_radps, 0.0, 0.0]
    )
    joint = np.array([geometry.joint1_x_m, 0.0, 0.0])
    v_joint = chain_velocity(velocity_ref_mps, omega_rear, joint)
    positions = geometry.wheel_positions_m()
    axle, drive = geometry.axle_directions(), geometry.drive_directions()
    velocity = np.empty((7, 3))
    rates = np.empty((7, 3))
    for i in range(7):
        if FRONT_PART[i]:
            arm = rel @ (positions[i] - joint)
            velocity[i] = chain_velocity(v_joint, sigma_front, arm)
            rates[i] = sigma_front
            axle[i], drive[i] = rel @ axle[i], rel @ drive[i]
        else:
            velocity[i] = chain_velocity(velocity_ref_mps, omega_rear, positions[i])
            rates[i] = omega_rear
    return PartKinematics(velocity, rates, axle, drive)


def scale_to_running_speed(velocity_mps: FloatArray, v0_mps: float) -> tuple[FloatArray, float]:
    """Eq. (14)-(15): one factor ``c = min_i c_i`` with ``c_i = V0 / |v_i|`` where ``|v_i| > V0``
    (else 1) applied to every wheel velocity (n, 3) in [m/s]; returns (scaled, c)."""
    speed = np.linalg.norm(velocity_mps, axis=1)
    factors = np.where(speed > abs(v0_mps), abs(v0_mps) / np.maximum(speed, 1e-300), 1.0)
    c = float(np.min(factors)) if factors.size else 1.0
    return np.asarray(velocity_mps * c), c


def spin_references(kin: PartKinematics, velocity_mps: FloatArray, radius_m: float) -> FloatArray:
    """Eq. (16)-(18): motor rate references (7,) in [rad/s].

    The wheel frame's x axis is the drive direction turned about the axle by ``alpha`` so that the
    velocity lies along it (eq. 18), hence the rolling speed is the velocity's length in the
    wheel's plane, signed by its component along the drive direction (ties roll forward); the
    part's own rotation about the axle is taken off (eq. 17). Steps lie across the direction of
    travel, so only the wheels driving along x meet a slope: the sideways wheel's ground stays
    level and it rolls at its drive-direction speed (``alpha = 0``)."""
    along_axle = np.sum(velocity_mps * kin.axle, axis=1)
    along_drive = np.sum(velocity_mps * kin.drive, axis=1)
    in_plane = velocity_mps - along_axle[:, None] * kin.axle
    sign = np.where(along_drive < 0.0, -1.0, 1.0)
    tilted = sign * np.linalg.norm(in_plane, axis=1)
    rolling = np.where(np.abs(kin.drive[:, 0]) > 0.5, tilted, along_drive) / radius_m
    return np.asarray(rolling - np.sum(kin.part_rate_radps * kin.axle, axis=1))


@dataclass(frozen=True)
class WheelReferences:
    """References of one control tick."""

    rate_radps: FloatArray
    """(7,) motor rate reference of each wheel in [rad/s]."""
    scale: float
    """The factor ``c`` of eq. (15) (1: no wheel had to be slowed)."""
    velocity_mps: FloatArray
    """(7, 3) scaled wheel velocities in [m/s] in {4}."""


def proposed_references(
    velocity_ref_mps: FloatArray, config: BodyConfiguration, geometry: OmniGeometry
) -> WheelReferences:
    """The proposed method (Fig. 4): chain, scaling to V0, references in each wheel's frame.

    ``velocity_ref_mps`` (3,) in [m/s] is the wanted velocity of the middle axle's centre in {4}
    (``(V0, 0, 0)`` when climbing, eq. 13; any horizontal twist when writing, with the yaw rate
    in ``config.rear_rate_radps[2]``)."""
    kin = wheel_kinematics(np.asarray(velocity_ref_mps, dtype=np.float64), config, geometry)
    scaled, c = scale_to_running_speed(kin.velocity_mps, geometry.running_speed_mps)
    return WheelReferences(spin_references(kin, scaled, geometry.wheel_radius_m), c, scaled)


def standard_references(geometry: OmniGeometry, direction: float = 1.0) -> FloatArray:
    """The standard method: the fixed reference ``V0 / r`` in [rad/s] for every x-driving wheel
    (``direction`` -1 drives backwards), 0 for the sideways wheel; (7,)."""
    drive_x = geometry.drive_directions()[:, 0]
    return np.asarray(direction * drive_x * geometry.running_speed_mps / geometry.wheel_radius_m)


def slip_ratio(radius_m: float, spin_radps: FloatArray, speed_mps: FloatArray) -> FloatArray:
    """Eq. (19): ``(r w - v_w) / (r w)`` per sample, ``w`` the wheel's spin in [rad/s], ``v_w``
    the speed in [m/s] its centre moves over the ground."""
    rw = radius_m * np.asarray(spin_radps, dtype=np.float64)
    return np.asarray((rw - speed_mps) / rw)


def rotation_error_ratio(reference_radps: FloatArray, spin_radps: FloatArray) -> FloatArray:
    """Eq. (20): ``(w_ref - w) / w`` per sample, rates in [rad/s]."""
    w = np.asarray(spin_radps, dtype=np.float64)
    return np.asarray((np.asarray(reference_radps) - w) / w)
