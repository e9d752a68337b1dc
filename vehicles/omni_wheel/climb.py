"""Step climbing, standard against proposed wheel control (the paper's simulation, section 3.1).

The vehicle starts on the flat in front of a step across its path and drives forward at V0. It has
climbed when every wheel stands on the step. Slip (eq. 19) and rotation error (eq. 20) are logged
per wheel while the climb lasts (from the front wheels' first touch of the step face until the
rear wheels are up) and averaged per wheel group (front, middle, rear) as in the paper's Table 2.
Only the six wheels driving along x count: the paper's model is planar, and the sideways wheel
moves along its axle on its rollers in a forward climb (its eq. 19 would compare a spin held at
zero with the front axle's rise).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from vehicles.omni_wheel.geometry import WHEEL_GROUP, OmniGeometry
from vehicles.omni_wheel.sim import OmniWorld, Sensed, TrueState
from vehicles.omni_wheel.terrain import Step, Terrain
from vehicles.omni_wheel.wheel_control import (
    BodyConfiguration,
    proposed_references,
    rotation_error_ratio,
    slip_ratio,
    standard_references,
)

FloatArray = NDArray[np.float64]
Method = Literal["standard", "proposed"]
METHODS: tuple[Method, ...] = ("standard", "proposed")

TABLE_1 = OmniGeometry()
"""The prototype as Table 1 gives it."""
STEP_EDGE_X_M = 0.6
"""World x in [m] of the step edge in a climb run (the vehicle's middle axle starts at 0)."""
RATIO_CAP = 1.0
"""Per-sample slip and rotation error ratios are capped at 100 % before averaging (near-zero
rates make them unbounded)."""


def configuration_of(sensed: Sensed, yaw_rate_radps: float = 0.0) -> BodyConfiguration:
    """The body configuration the proposed method uses: potentiometers of joint 1 and the rear
    part's roll and pitch rates (its yaw rate is the commanded one, never fed back)."""
    return BodyConfiguration(
        rear_rate_radps=(float(sensed.gyro_radps[0]), float(sensed.gyro_radps[1]), yaw_rate_radps),
        joint_pitch_rad=float(sensed.joint_angles_rad[0]),
        joint_roll_rad=float(sensed.joint_angles_rad[1]),
        joint_pitch_rate_radps=float(sensed.joint_rates_radps[0]),
        joint_roll_rate_radps=float(sensed.joint_rates_radps[1]),
    )


def controller(method: Method, geometry: OmniGeometry) -> Callable[[Sensed], FloatArray]:
    """Wheel rate references (7,) in [rad/s] from the sensors, driving forward at V0."""
    if method == "standard":
        fixed = standard_references(geometry)
        return lambda sensed: fixed
    v_ref = np.array([geometry.running_speed_mps, 0.0, 0.0])
    return lambda sensed: proposed_references(v_ref, configuration_of(sensed), geometry).rate_radps


@dataclass(frozen=True)
class ClimbResult:
    """One climb run."""

    method: Method
    """Wheel control method."""
    step_height_m: float
    """Height in [m] of the step."""
    climbed: bool
    """Every wheel stood on the step before the time ran out."""
    duration_s: float
    """Simulated time in [s] of the run."""
    slip_per_wheel: FloatArray
    """(7,) mean |slip ratio| per wheel during the climb (NaN where never measurable, and for the
    sideways wheel)."""
    rotation_error_per_wheel: FloatArray
    """(7,) mean |rotation error ratio| per wheel during the climb."""
    log: dict[str, FloatArray]
    """Time series: ``t_s`` (K,), ``slip`` and ``rotation_error`` (K, 7), ``base_m_enu`` (K, 3),
    ``reference_radps`` (K, 7), ``joint_pitch_rad`` (K,) (true pitch of free joint 1)."""

    def by_group(self, values: FloatArray) -> dict[str, float]:
        """Front / middle / rear means of a per-wheel figure, and their average."""
        out: dict[str, float] = {}
        for group in ("front", "middle", "rear"):
            members = [values[i] for i, g in enumerate(WHEEL_GROUP) if g == group]
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)
                out[group] = float(np.nanmean(members))
        out["average"] = float(np.mean([out["front"], out["middle"], out["rear"]]))
        return out


def rolling_speed_mps(truth: TrueState) -> FloatArray:
    """(7,) speed in [m/s] of each wheel centre in its wheel's plane (eq. 19's ``v_w``), signed as
    the spin that would roll it so: along the wheel's drive direction (``axle x up``) where it
    moves mostly horizontally, as the wheel spins where it moves mostly vertically (up or down a
    riser, where only the spin tells which way it rolls). Unsigned, a wheel rolling backwards
    (writing, a route going west) had a slip of 200 %."""
    velocity, axle = truth.hub_velocity_mps_enu, truth.axle_enu
    along_axle = np.sum(velocity * axle, axis=1)
    in_plane = velocity - along_axle[:, None] * axle
    speed = np.linalg.norm(in_plane, axis=1)
    drive = np.cross(axle, np.array([0.0, 0.0, 1.0]))
    forward = np.sum(in_plane * drive, axis=1)
    horizontal = np.abs(forward) >= np.abs(in_plane[:, 2])
    sign = np.where(horizontal, np.sign(forward), np.sign(truth.wheel_spin_radps))
    return np.asarray(np.where(sign < 0.0, -speed, speed))


def wheel_ratios(
    truth: TrueState, refs: FloatArray, geometry: OmniGeometry
) -> tuple[FloatArray, FloatArray]:
    """Per-wheel |slip| (eq. 19, from the wheel's absolute spin and its centre's signed speed in
    the wheel plane, :func:`rolling_speed_mps`) and |rotation error| (eq. 20, motor rate against
    ``refs``) at one tick, capped at :data:`RATIO_CAP`; NaN where the wheel is nearly still."""
    r, v0 = geometry.wheel_radius_m, geometry.running_speed_mps
    spin = truth.wheel_spin_radps
    moving = np.abs(r * spin) > 0.1 * v0
    speed = rolling_speed_mps(truth)
    slip = np.where(moving, slip_ratio(r, np.where(moving, spin, 1.0), speed), np.nan)
    turning = np.abs(r * truth.motor_rate_radps) > 0.1 * v0
    rate = np.where(turning, truth.motor_rate_radps, 1.0)
    error = np.where(turning, rotation_error_ratio(refs, rate), np.nan)
    return np.minimum(np.abs(slip), RATIO_CAP), np.minimum(np.abs(error), RATIO_CAP)


def climb(
    method: Method,
    step_height_m: float,
    *,
    geometry: OmniGeometry = TABLE_1,
    seed: int = 0,
    time_limit_s: float = 14.0,
) -> ClimbResult:
    """Drive over a step of ``step_height_m`` [m] with ``method``; see the module docstring."""
    terrain = Terrain(steps=(Step(STEP_EDGE_X_M, step_height_m),))
    world = OmniWorld(geometry, terrain, ((0.0, 0.0, 0.0, 0.0),), seed=seed)
    control = controller(method, geometry)
    r = geometry.wheel_radius_m
    along_x = np.abs(geometry.drive_directions()[:, 0]) > 0.5
    keys = ("t_s", "slip", "rotation_error", "base_m_enu", "reference_radps", "joint_pitch_rad")
    logs: dict[str, list[FloatArray]] = {k: [] for k in keys}
    climbing = climbed = False
    while world.t_s < time_limit_s:
        refs = control(world.sense(0))
        world.step(refs[None, :])
        truth = world.truth(0)
        climbing = climbing or bool(truth.hub_m_enu[0, 0] > STEP_EDGE_X_M - r - 0.005)
        climbed = bool(np.all(truth.hub_m_enu[:, 2] > step_height_m + 0.5 * r)) and bool(
            np.all(truth.hub_m_enu[:, 0] > STEP_EDGE_X_M + 0.5 * r)
        )
        if climbing:
            slip, error = wheel_ratios(truth, refs, geometry)
            slip[~along_x], error[~along_x] = np.nan, np.nan
            for key, value in (
                ("t_s", np.array(world.t_s)),
                ("slip", slip),
                ("rotation_error", error),
                ("base_m_enu", truth.base_m_enu),
                ("reference_radps", refs),
                ("joint_pitch_rad", np.array(truth.joint_angles_rad[0])),
            ):
                logs[key].append(value)
        if climbed:
            break
    log = {k: np.asarray(v, dtype=np.float64) for k, v in logs.items()}
    nan7 = np.full(7, np.nan)
    with warnings.catch_warnings():  # a wheel that never turned has no ratio: NaN
        warnings.simplefilter("ignore", RuntimeWarning)
        slip_mean = np.nanmean(log["slip"], axis=0) if log["slip"].size else nan7
        error_mean = np.nanmean(log["rotation_error"], axis=0) if log["slip"].size else nan7
    return ClimbResult(method, step_height_m, climbed, world.t_s, slip_mean, error_mean, log)
