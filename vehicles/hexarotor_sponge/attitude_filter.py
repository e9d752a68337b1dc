"""The attitude the controller flies by: the gyro's rates integrated, pulled slowly towards the
motion capture's attitude (a complementary filter, as a flight controller's estimator does).

The motion capture reads the attitude with 3 mrad of noise per axis and tick. Used raw, that noise
turns the 34 N of hover thrust by as much, 0.1 N of white force across the wall's normal at every
tick, and through the 0.52 m lever to the tip it moves the tip's position 1.6 mm: letter A,
seed 0, attitude noise alone added 19 % of the contact-aware loop's force MSE with a 0.2 s filter
and 3 % with this 1 s one. The simulated gyro has no bias; a real one drifts slowly, which the
pull towards the motion capture removes at the same time constant.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from vehicles.hexarotor_sponge.rotations import rotation_of, vee

FloatArray = NDArray[np.float64]

TIME_CONSTANT_S = 1.0
"""How slowly the estimate follows the motion capture's attitude, [s] (bench_wall, letter A,
seed 0: force RMSE of the contact-aware loop 0.0358 N at 0.2 s, 0.0338 at 0.5 s, 0.0334 at 1 s)."""


class AttitudeFilter:
    """One filter per run; starts at the first attitude it is given."""

    def __init__(self, dt_s: float, time_constant_s: float = TIME_CONSTANT_S) -> None:
        self.dt_s = dt_s
        self.gain = min(1.0, dt_s / time_constant_s)
        self._rotation: FloatArray | None = None
        self._ticks = 0

    def update(self, measured_body_to_enu: FloatArray, omega_radps_body: FloatArray) -> FloatArray:
        """The estimated body-to-ENU rotation (3, 3) after one control period of the body
        rates ``omega_radps_body`` [rad/s], corrected towards the measured rotation. The first
        ticks average the measurements (gain 1/n till it falls to the filter's), so the start
        does not keep the first reading's noise for a time constant."""
        self._ticks += 1
        if self._rotation is None:
            self._rotation = np.asarray(measured_body_to_enu, dtype=np.float64)
            return self._rotation
        predicted = self._rotation @ rotation_of(omega_radps_body * self.dt_s)
        diff = predicted.T @ measured_body_to_enu
        error = 0.5 * vee(diff - diff.T)
        self._rotation = predicted @ rotation_of(max(self.gain, 1.0 / self._ticks) * error)
        return self._rotation
