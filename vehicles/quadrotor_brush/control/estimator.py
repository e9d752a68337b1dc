"""Position, velocity and disturbance estimate from delayed, noisy motion capture.

Per axis a steady-state Kalman filter on ``[p, v, d]`` with ``dv/dt = a - c v + d``: ``c`` a known
linear drag (zero if not modelled), ``a`` the
acceleration the vehicle achieves (the commanded one through a first-order model of the inner loop
and motors), ``d`` a slowly varying disturbance (wind, drag, ground effect, model error) that the
controller may cancel. The filter lives at the frame's capture time and is predicted forward over
the latency to the current tick.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicles.quadrotor_brush.control.errors import ControlError

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class EstimatorConfig:
    """Noise model and timing of the mocap filter."""

    measurement_std_m: float = 0.0003
    """Assumed position noise per axis in [m]."""
    accel_noise_mps2: float = 0.3
    """Process noise on the acceleration (unmodelled, white) in [m/s^2 / sqrt(Hz)] scale."""
    disturbance_rate_mps3: float = 3.0
    """Random-walk rate of the disturbance in [m/s^3 / sqrt(Hz)] scale."""
    latency_s: float = 0.005
    """Mocap latency in [s] to predict over."""
    actuator_time_constant_s: tuple[float, float, float] = (0.056, 0.056, 0.02)
    """First-order model of command -> achieved acceleration per axis in [s]."""
    drag_per_s: tuple[float, float, float] = (0.35, 0.35, 0.25)
    """Known (identified) linear rotor drag per unit mass per axis in [1/s]: ``dv/dt`` gets
    ``- drag * v``. Zero if not modelled."""

    def __post_init__(self) -> None:
        for name in ("measurement_std_m", "accel_noise_mps2", "disturbance_rate_mps3"):
            if not getattr(self, name) > 0.0:
                raise ControlError("must be positive", field=name)
        if self.latency_s < 0.0:
            raise ControlError("must be non-negative", field="latency_s")


def steady_state_gain(config: EstimatorConfig, dt_s: float) -> FloatArray:
    """Steady-state Kalman gain (3,) for ``[p, v, d]`` sampled every ``dt_s``."""
    f = np.array([[1.0, dt_s, 0.5 * dt_s**2], [0.0, 1.0, dt_s], [0.0, 0.0, 1.0]])
    q = np.diag([0.0, config.accel_noise_mps2**2 * dt_s, config.disturbance_rate_mps3**2 * dt_s])
    r = config.measurement_std_m**2
    p = np.eye(3) * 1.0
    gain = np.zeros(3)
    for _ in range(5000):
        pred = f @ p @ f.T + q
        s = pred[0, 0] + r
        new_gain = pred[:, 0] / s
        p = pred - np.outer(new_gain, pred[0, :])
        if np.max(np.abs(new_gain - gain)) < 1e-13:
            gain = new_gain
            break
        gain = new_gain
    return gain


class MocapEstimator:
    """Vectorised filter for N vehicles; call :meth:`update` once per control tick."""

    _ROWS = ("_p", "_v", "_d", "_a", "position_m_enu", "velocity_mps_enu")
    """The arrays with one row per vehicle (the rest is the same for all)."""

    def __init__(
        self, config: EstimatorConfig, dt_s: float, initial_position_m_enu: FloatArray
    ) -> None:
        self.config = config
        self.dt_s = dt_s
        k = steady_state_gain(config, dt_s)
        self._k = (float(k[0]), float(k[1]), float(k[2]))
        p0 = np.array(initial_position_m_enu, dtype=np.float64).reshape(-1, 3)
        self._p = p0.copy()
        self._v = np.zeros_like(p0)
        self._d = np.zeros_like(p0)
        self._a = np.zeros_like(p0)
        tau = np.asarray(config.actuator_time_constant_s, dtype=np.float64)
        self._lag = 1.0 - np.exp(-dt_s / tau)
        self._drag = np.asarray(config.drag_per_s, dtype=np.float64)
        self.position_m_enu = p0.copy()
        """Estimate at the current tick in [m], shape (N, 3)."""
        self.velocity_mps_enu = np.zeros_like(p0)
        """Estimate at the current tick in [m/s], shape (N, 3)."""

    @property
    def disturbance_mps2_enu(self) -> FloatArray:
        """Estimated external acceleration in [m/s^2], shape (N, 3)."""
        return self._d

    def update(self, measured_m_enu: FloatArray, last_command_mps2_enu: FloatArray) -> None:
        """Fuse a frame and advance: ``last_command`` is what was applied since the last tick."""
        dt = self.dt_s
        acc = self._a + self._d - self._drag * self._v
        p = self._p + self._v * dt + (0.5 * dt * dt) * acc
        v = self._v + acc * dt
        innov = measured_m_enu - p
        k0, k1, k2 = self._k
        self._p = p + k0 * innov
        self._v = v + k1 * innov
        self._d = self._d + k2 * innov
        self._a = self._a + self._lag * (last_command_mps2_enu - self._a)
        lat = self.config.latency_s
        acc = self._a + self._d - self._drag * self._v
        self.position_m_enu = self._p + self._v * lat + (0.5 * lat * lat) * acc
        self.velocity_mps_enu = self._v + acc * lat

    def take(self, rows: Sequence[int]) -> MocapEstimator:
        """The filter of vehicles ``rows`` (in that order), each as it stands."""
        index = list(rows)
        out = copy.copy(self)
        for name in self._ROWS:
            setattr(out, name, getattr(self, name)[index])
        return out

    @classmethod
    def stack(cls, parts: Sequence[MocapEstimator]) -> MocapEstimator:
        """The filters of ``parts`` (same configuration and tick) as one, in order."""
        out = copy.copy(parts[0])
        for name in cls._ROWS:
            setattr(out, name, np.concatenate([getattr(p, name) for p in parts]))
        return out
