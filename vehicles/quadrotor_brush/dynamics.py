"""Translational quadrotor dynamics with a closed inner attitude loop, vectorised over N vehicles.

Model per vehicle (world ENU, body FLU, ZYX Euler angles roll phi, pitch theta, yaw psi):

- inner loop: each angle follows its command as a second-order system (natural frequency about
  25 rad/s, Phang 2015 section 2), commands clamped to the maximum tilt;
- collective thrust follows the throttle through a first-order motor lag, saturated to
  ``[0, thrust_to_weight * g]``; throttle -> specific thrust through the plant gain of eq. 2;
- translation: ``dv/dt = n * T * k_ge - D/m (v - w) - g e_z`` with ``n`` the body z axis, ``k_ge``
  the ground-effect gain and ``w`` the wind.

The linear inner-loop and motor parts are discretised exactly (zero-order hold over a physics
step); the translation holds thrust and wind over a physics step, integrates the linear drag
exactly for the velocity and steps the position with the new velocity (semi-implicit).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, fields

import numpy as np
from numpy.typing import NDArray

from sim.errors import SimError
from vehicles.quadrotor_brush.params import QuadrotorParams

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class InnerLoopCommand:
    """Inputs of the inner loop for N vehicles, held for one control tick."""

    throttle: FloatArray
    """Throttle in plant units, shape (N,); specific thrust = throttle / throttle_per_mps2."""
    roll_rad: FloatArray
    """Roll command about body x (FLU, right-hand) in [rad], shape (N,)."""
    pitch_rad: FloatArray
    """Pitch command about body y (FLU: positive tilts thrust towards +x) in [rad], shape (N,)."""
    yaw_rad: FloatArray
    """Heading command about world z in [rad], shape (N,)."""


@dataclass
class QuadrotorState:
    """Mutable state of N vehicles; the world updates these arrays in place each step."""

    position_m_enu: FloatArray
    """Vehicle reference point in [m], shape (N, 3)."""
    velocity_mps_enu: FloatArray
    """Velocity in [m/s], shape (N, 3)."""
    attitude_rad: FloatArray
    """Roll, pitch, yaw in [rad], shape (N, 3)."""
    attitude_rate_radps: FloatArray
    """Rates of roll, pitch, yaw in [rad/s], shape (N, 3)."""
    thrust_mps2: FloatArray
    """Collective rotor thrust per unit mass, out of ground effect, in [m/s^2], shape (N,)."""
    body_z_enu: FloatArray
    """Unit body z axis (thrust direction) in the world, shape (N, 3)."""

    def take(self, rows: Sequence[int]) -> QuadrotorState:
        """The state of vehicles ``rows`` (arrays copied)."""
        index = list(rows)
        return QuadrotorState(*(getattr(self, f.name)[index] for f in fields(self)))

    @classmethod
    def stack(cls, parts: Sequence[QuadrotorState]) -> QuadrotorState:
        """The vehicles of ``parts``, in order, as one state."""
        return cls(*(np.concatenate([getattr(p, f.name) for p in parts]) for f in fields(cls)))

    def copy(self) -> QuadrotorState:
        """A deep copy (arrays copied)."""
        return QuadrotorState(
            self.position_m_enu.copy(),
            self.velocity_mps_enu.copy(),
            self.attitude_rad.copy(),
            self.attitude_rate_radps.copy(),
            self.thrust_mps2.copy(),
            self.body_z_enu.copy(),
        )


def expm_small(matrix: FloatArray) -> FloatArray:
    """Matrix exponential of a small matrix by scaling, Taylor series and squaring."""
    norm = float(np.max(np.sum(np.abs(matrix), axis=1)))
    squarings = max(0, int(np.ceil(np.log2(norm / 0.25))) if norm > 0.25 else 0)
    scaled = matrix / (2.0**squarings)
    result = np.eye(matrix.shape[0])
    term = np.eye(matrix.shape[0])
    for k in range(1, 20):
        term = term @ scaled / k
        result = result + term
    for _ in range(squarings):
        result = result @ result
    return result


def body_z_axis(attitude_rad: FloatArray) -> FloatArray:
    """Body z axis in the world for ZYX Euler angles (roll, pitch, yaw), shape (N, 3)."""
    s = np.sin(attitude_rad).T
    c = np.cos(attitude_rad).T
    sr, sp, sy = s
    cr, cp, cy = c
    spcr = sp * cr
    out = np.empty((3, attitude_rad.shape[0]))
    np.multiply(cy, spcr, out=out[0])
    out[0] += sy * sr
    np.multiply(sy, spcr, out=out[1])
    out[1] -= cy * sr
    np.multiply(cp, cr, out=out[2])
    return out.T


def ground_effect_gain(height_above_board_m: FloatArray, rotor_radius_m: float) -> FloatArray:
    """Cheeseman-Bennett thrust ratio T_IGE / T_OGE = 1 / (1 - (R / 4z)^2), z >= R/2."""
    z = np.maximum(height_above_board_m, 0.5 * rotor_radius_m)
    ratio = rotor_radius_m / (4.0 * z)
    gain: FloatArray = 1.0 / (1.0 - ratio * ratio)
    return gain


def _clamp(values: FloatArray, low: float, high: float) -> FloatArray:
    out: FloatArray = np.minimum(np.maximum(values, low), high)
    return out


class QuadrotorDynamics:
    """Precomputed discrete-time coefficients; :meth:`advance` steps N vehicles one control tick.

    Commands are held over a tick, so the linear inner-loop and motor states at every physics step
    of the tick are closed-form in the tick's initial state (powers of the step transition,
    precomputed); only the translation is stepped, with the drag integrated exactly.
    """

    def __init__(self, params: QuadrotorParams, physics_dt_s: float, substeps: int) -> None:
        if not physics_dt_s > 0.0:
            raise SimError("must be positive", field="physics_dt_s")
        self.params = params
        self.dt_s = physics_dt_s
        self.substeps = substeps
        wn = params.attitude_natural_freq_radps
        zeta = params.attitude_damping
        aug = np.zeros((3, 3))
        aug[0, 1] = 1.0
        aug[1, 0] = -wn * wn
        aug[1, 1] = -2.0 * zeta * wn
        aug[1, 2] = wn * wn
        step = expm_small(aug * physics_dt_s)
        powers = [np.linalg.matrix_power(step, j) for j in range(1, substeps + 1)]
        # angle_j = A[j] angle_0 + B[j] rate_0 + C[j] cmd (j = 1..S), shape (S, 1, 1)
        self._angle_coef = tuple(
            np.array([m[0, k] for m in powers])[:, None, None] for k in range(3)
        )
        self._rate_coef = tuple(float(powers[-1][1, k]) for k in range(3))
        alpha = np.exp(-physics_dt_s * np.arange(1, substeps + 1) / params.motor_time_constant_s)
        self._motor_keep = alpha[:, None]
        drag = np.asarray(params.drag_n_per_mps, dtype=np.float64) / params.mass_kg
        self._drag_per_kg = drag
        self._drag_keep = np.exp(-drag * physics_dt_s)
        self._drag_gain = np.where(
            drag > 0.0, (1.0 - self._drag_keep) / np.maximum(drag, 1e-300), physics_dt_s
        )

    def thrust_command_mps2(self, throttle: FloatArray) -> FloatArray:
        """Saturated specific thrust demanded by a throttle, shape (N,)."""
        p = self.params
        demanded = np.asarray(throttle, dtype=np.float64) * (1.0 / p.throttle_per_mps2)
        return _clamp(demanded, 0.0, p.max_specific_thrust_mps2)

    def attitude_command(self, command: InnerLoopCommand) -> FloatArray:
        """Clamped (roll, pitch, yaw) commands, shape (N, 3)."""
        tilt = self.params.max_tilt_rad
        cmd = np.empty((np.shape(command.throttle)[0], 3))
        cmd[:, 0] = command.roll_rad
        cmd[:, 1] = command.pitch_rad
        cmd[:, :2] = _clamp(cmd[:, :2], -tilt, tilt)
        cmd[:, 2] = command.yaw_rad
        return cmd

    def advance(
        self,
        state: QuadrotorState,
        command: InnerLoopCommand,
        wind_mps_enu: FloatArray,
        ground_gain: FloatArray,
        capture_after: int | None = None,
    ) -> FloatArray | None:
        """Advance ``state`` in place by one control tick (``substeps`` physics steps).

        Returns the positions after ``capture_after`` physics steps (0 = at the start) when
        asked, for the motion-capture delay line.
        """
        cmd = self.attitude_command(command)
        thrust_cmd = self.thrust_command_mps2(command.throttle)
        att0, rate0, thr0 = state.attitude_rad, state.attitude_rate_radps, state.thrust_mps2
        ca, cr, cu = self._angle_coef
        att = ca * att0 + cr * rate0 + cu * cmd  # (S, N, 3)
        ra, rr, ru = self._rate_coef
        rate = ra * att0 + rr * rate0 + ru * cmd
        thr = thrust_cmd + (thr0 - thrust_cmd) * self._motor_keep  # (S, N)
        n = body_z_axis(att.reshape(-1, 3)).reshape(att.shape)
        force = n * (thr * ground_gain)[:, :, None]
        force[:, :, 2] -= self.params.gravity_mps2
        force += self._drag_per_kg * wind_mps_enu
        force *= self._drag_gain
        keep, h = self._drag_keep, self.dt_s
        p, v = state.position_m_enu, state.velocity_mps_enu
        captured = p if capture_after == 0 else None
        for j in range(self.substeps):
            v = keep * v + force[j]
            p = p + v * h
            if j + 1 == capture_after:
                captured = p
        state.attitude_rad, state.attitude_rate_radps, state.thrust_mps2 = att[-1], rate, thr[-1]
        state.position_m_enu, state.velocity_mps_enu, state.body_z_enu = p, v, n[-1]
        return captured
