"""The force on the vehicle that neither the rotors nor the arm explain (wind, gusts, misdirected
thrust), estimated from the motion capture: our extension of the paper's motion control (eq. 12
has only the integral ``K_i int e_q`` against such forces).

The base alone is a rigid body under known forces: ``m_b a = u + f_arm + m_b g + d``, with ``u``
the control force the controller commanded, ``f_arm`` what the arm pushes on the base (the F/T
sensor reads it, contact and friction included, whatever the contact model says) and ``d`` the
unknown. A Kalman filter per world axis of the base's position, velocity and ``d`` fuses that
model with the motion capture's position and velocity. Because the arm's force is measured, ``d``
holds no contact force: cancelling it rejects the wind and leaves the friction to the contact
model (ours) or to no one (the control baseline), so the two loops stay the paper's ablation.

Why: the 1 m/s wind with 0.3 m/s gusts (``fly_settings.WorldNoise``) pushes the 3.5 kg vehicle
with 0.05 N of force varying over a second; at 60 N/m that is a millimetre across a 10 mm line,
and the position integral (25 N/(m s)) takes seconds to take it back (letter I, seed 2, wind
alone: flown IoU 0.83 against 0.99 calm).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class MotionSensorSpec:
    """The noise the filter assumes of the motion capture and of its model, standard deviations
    (the values the simulated world draws, ``fly_settings.WorldNoise``, as a data sheet would
    state them)."""

    position_m: float = 1.0e-3
    """Base position from motion capture in [m]."""
    velocity_mps: float = 5.0e-3
    """Base velocity from motion capture in [m/s]."""
    acceleration_mps2: float = 0.05
    """Unmodelled acceleration per tick in [m/s^2]: hover thrust misdirected by the attitude
    estimate's error (34 N times 3 mrad: 0.1 N) and the F/T sensor's 0.05 N of noise, over the
    3.2 kg base (``normal_observer.SensorSpec`` makes the same estimate)."""
    disturbance_rate_nps: float = 0.3
    """How fast the unknown force may drift in [N/s] per sqrt(s) of a random walk. The gusts'
    drag changes by rho C_d A |v| dv: 0.18 N per m/s at 1 m/s, 0.055 N for 0.3 m/s of gust with
    a 1 s correlation time, a drift of sqrt(2/1 s) 0.055 = 0.08 N/sqrt(s); chosen at a few
    times that: at 0.1 and 1.0 N/sqrt(s) the flown IoU of letters I, A, 永 (seeds 0, 1) moved
    by at most 0.01, the force RMSE by at most 0.001 N."""
    latency_s: float = 0.01
    """How old the motion capture's reading is in [s]: the filter predicts to the reading's
    time with the inputs of then."""


class DisturbanceObserver:
    """State per world axis (columns): the base's position in [m], velocity in [m/s] and the
    unknown force in [N]; one covariance serves the three axes (same model and noise)."""

    def __init__(self, base_mass_kg: float, dt_s: float, spec: MotionSensorSpec | None = None):
        self.spec = spec or MotionSensorSpec()
        m = base_mass_kg
        self._a = np.array([[1.0, dt_s, 0.5 * dt_s**2 / m], [0.0, 1.0, dt_s / m], [0.0, 0.0, 1.0]])
        self._b = np.array([0.5 * dt_s**2, dt_s, 0.0])
        s = self.spec
        acc = s.acceleration_mps2**2
        self._q = np.diag([0.25 * dt_s**4 * acc, dt_s**2 * acc, s.disturbance_rate_nps**2 * dt_s])
        lag = max(0, round(s.latency_s / dt_s))
        self._inputs: deque[FloatArray] = deque(maxlen=lag + 1)
        self.state = np.zeros((3, 3))
        self.cov = np.diag([s.position_m**2, s.velocity_mps**2, 1.0])
        self._started = False

    @property
    def force_n(self) -> FloatArray:
        """(3,) the estimated unknown force on the vehicle in [N], world ENU."""
        return np.asarray(self.state[2].copy())

    def update(
        self, position_m: FloatArray, velocity_mps: FloatArray, known_acceleration_mps2: FloatArray
    ) -> FloatArray:
        """One tick: predict over a control period under the known forces' acceleration (3,) in
        [m/s^2] (control force and arm force over the base's mass, and gravity) of the last
        period, delayed as the motion capture's reading is, then correct with the measured base
        position (3,) [m] and velocity (3,) [m/s]. Returns the estimated unknown force (3,) in
        [N] (as of the reading's time)."""
        self._inputs.append(np.asarray(known_acceleration_mps2, dtype=np.float64))
        if not self._started:
            self.state[0], self.state[1] = position_m, velocity_mps
            self._started = True
        else:
            self.state = self._a @ self.state + np.outer(self._b, self._inputs[0])
            self.cov = self._a @ self.cov @ self._a.T + self._q
        self._correct(0, position_m, self.spec.position_m)
        self._correct(1, velocity_mps, self.spec.velocity_mps)
        return self.force_n

    def _correct(self, row: int, value: FloatArray, std: float) -> None:
        """Kalman update of every axis with a measurement of state ``row``."""
        gain = self.cov[:, row] / (self.cov[row, row] + std**2)
        self.state = self.state + np.outer(gain, value - self.state[row])
        self.cov = self.cov - np.outer(gain, self.cov[row, :])
