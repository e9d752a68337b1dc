"""The writing-quadrotor position controller: mocap filter + RPT outer loop + G_c conversion.

Per tick: fuse the mocap frame, form the RPT law of eq. 8 per axis (error integral, position and
velocity feedback, acceleration feed-forward), optionally cancel the estimated disturbance, and
convert to throttle, roll and pitch through G_c. Optionally it also aims the brush tip rather than
the body: the brush hangs along the body z axis, so a tilted vehicle writes ``lever * tilt`` away
from its reference point; the vehicle reference is shifted by the tilt the reference acceleration
and the (low-passed) disturbance will demand.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from vehicles.quadrotor_brush.control.config import ControllerConfig
from vehicles.quadrotor_brush.control.errors import ControlError
from vehicles.quadrotor_brush.control.estimator import MocapEstimator
from vehicles.quadrotor_brush.control.inner import InnerLoopSetpoint, inner_setpoint
from vehicles.quadrotor_brush.control.tip import (
    body_reference_for_tip,
    lag_compensated,
    tip_filter_poles,
)

FloatArray = NDArray[np.float64]


def body_reference(
    config: ControllerConfig,
    position_m_enu: FloatArray,
    velocity_mps_enu: FloatArray,
    acceleration_mps2_enu: FloatArray,
    dt_s: float,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The whole reference (K, ..., 3) as the controller should be fed it, tick by tick.

    Aims the brush tip (:func:`vehicles.quadrotor_brush.control.tip.body_reference_for_tip`, when
    ``brush_lever_m > 0``) and leads the acceleration feed-forward by the inner loop's lag
    (:func:`vehicles.quadrotor_brush.control.tip.lag_compensated`). Needs the reference in
    advance, which a planned trajectory is.
    """
    p, v, a = body_reference_for_tip(
        position_m_enu,
        velocity_mps_enu,
        acceleration_mps2_enu,
        dt_s,
        config.brush_lever_m,
        config.gravity_mps2,
        config.estimator.drag_per_s[:2],
    )
    lead = lag_compensated(a, dt_s, config.feedforward_lead_s, config.feedforward_second_order_s2)
    return p, v, lead


@dataclass(frozen=True)
class ReferenceTick:
    """Reference of N vehicles at one tick (world ENU, SI units)."""

    position_m_enu: FloatArray
    """Body reference point in [m], shape (N, 3) (after the tip preview when aiming the tip)."""
    velocity_mps_enu: FloatArray
    """Shape (N, 3)."""
    acceleration_mps2_enu: FloatArray
    """Shape (N, 3)."""
    yaw_rad: FloatArray | None = None
    """Shape (N,) or None (zero heading)."""


def _lever_poles(config: ControllerConfig) -> FloatArray:
    """Pole per axis of the disturbance low-pass for the tip shift in [rad/s]."""
    if config.lever_filter_bandwidth_radps is not None:
        return np.full(3, config.lever_filter_bandwidth_radps)
    if config.brush_lever_m == 0.0:
        return np.zeros(3)
    drag = config.estimator.drag_per_s
    return np.array(
        [tip_filter_poles(config.brush_lever_m, c, config.gravity_mps2)[0] for c in drag]
    )


class PositionController:
    """Vectorised controller for N vehicles; call :meth:`update` once per control tick."""

    _ROWS = ("integral_m_s", "accel_cmd_mps2_enu", "target_m_enu", "_slow_disturbance")
    """The arrays with one row per vehicle, besides the estimator's."""

    def __init__(
        self,
        config: ControllerConfig,
        dt_s: float,
        initial_position_m_enu: FloatArray,
    ) -> None:
        if not dt_s > 0.0:
            raise ControlError("must be positive", field="dt_s")
        self.config = config
        self.dt_s = dt_s
        p0 = np.array(initial_position_m_enu, dtype=np.float64).reshape(-1, 3)
        self.n_vehicles = p0.shape[0]
        self.estimator = MocapEstimator(config.estimator, dt_s, p0)
        self._ki, self._kp, self._kd = config.gains.vectors()
        self._drag = np.asarray(config.estimator.drag_per_s, dtype=np.float64)
        self._integral_cap = config.integral_limit_mps2 / self._ki
        self.integral_m_s = np.zeros_like(p0)
        """Error integral per axis in [m s], shape (N, 3)."""
        self.accel_cmd_mps2_enu = np.zeros_like(p0)
        """Last acceleration command (without gravity) in [m/s^2], shape (N, 3)."""
        self.target_m_enu = p0.copy()
        """Last vehicle position target (reference after tip aiming), shape (N, 3)."""
        self._slow_disturbance = np.zeros_like(p0)
        self._lever_step = 1.0 - np.exp(-dt_s * _lever_poles(config))

    def take(self, rows: Sequence[int]) -> PositionController:
        """The controller of vehicles ``rows`` (in that order), each as it stands."""
        index = list(rows)
        out = copy.copy(self)
        out.n_vehicles = len(index)
        out.estimator = self.estimator.take(index)
        for name in self._ROWS:
            setattr(out, name, getattr(self, name)[index])
        return out

    @classmethod
    def stack(cls, parts: Sequence[PositionController]) -> PositionController:
        """The controllers of ``parts`` as one, in order (same configuration and tick)."""
        first = parts[0]
        if any(p.config != first.config or p.dt_s != first.dt_s for p in parts):
            raise ControlError("controllers with different configurations", field="config")
        out = copy.copy(first)
        out.n_vehicles = sum(p.n_vehicles for p in parts)
        out.estimator = MocapEstimator.stack([p.estimator for p in parts])
        for name in cls._ROWS:
            setattr(out, name, np.concatenate([getattr(p, name) for p in parts]))
        return out

    def update(self, measured_m_enu: FloatArray, reference: ReferenceTick) -> InnerLoopSetpoint:
        """Fuse the mocap frame and return the inner-loop inputs for the coming tick."""
        cfg = self.config
        est = self.estimator
        est.update(measured_m_enu, self.accel_cmd_mps2_enu)
        p_ref, v_ref, a_ref = self._vehicle_reference(reference)
        error = p_ref - est.position_m_enu
        cap = self._integral_cap
        self.integral_m_s = np.minimum(np.maximum(self.integral_m_s + error * self.dt_s, -cap), cap)
        accel = (
            self._ki * self.integral_m_s
            + self._kp * error
            + self._kd * (v_ref - est.velocity_mps_enu)
            + a_ref
        )
        if cfg.disturbance_compensation:
            accel = accel - est.disturbance_mps2_enu + self._drag * v_ref
        self.accel_cmd_mps2_enu = accel
        self.target_m_enu = p_ref
        yaw = reference.yaw_rad if reference.yaw_rad is not None else np.zeros(self.n_vehicles)
        return inner_setpoint(
            accel,
            yaw,
            gravity_mps2=cfg.gravity_mps2,
            max_tilt_rad=cfg.max_tilt_rad,
            max_throttle=cfg.max_throttle,
        )

    def _vehicle_reference(
        self, reference: ReferenceTick
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Shift the horizontal reference against the tilt the disturbance demands, so that the
        brush tip (not the body) meets it; the reference's own accelerations are handled by the
        preview of :mod:`vehicles.quadrotor_brush.control.tip` before the flight.

        The shift is ``-lever / g`` times the disturbance through ``a / (s + a)``, the causal
        factor of the tip inverse
        (:func:`vehicles.quadrotor_brush.control.tip.tip_filter_poles`); its velocity is fed
        forward too."""
        lever = self.config.brush_lever_m
        p, v, a = (
            reference.position_m_enu,
            reference.velocity_mps_enu,
            reference.acceleration_mps2_enu,
        )
        if lever == 0.0:
            return p, v, a
        if self.config.disturbance_compensation:
            disturbance = self.estimator.disturbance_mps2_enu
        else:
            disturbance = -self._ki * self.integral_m_s
        x = self._slow_disturbance
        rate = (self._lever_step / self.dt_s) * (disturbance - x)
        self._slow_disturbance = x + self._lever_step * (disturbance - x)
        k = -lever / self.config.gravity_mps2
        p, v = p.copy(), v.copy()
        p[:, :2] += k * x[:, :2]
        v[:, :2] += k * rate[:, :2]
        return p, v, a
