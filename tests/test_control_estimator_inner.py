"""Mocap filter, G_c conversion and brush-tip preview: known answers and properties."""

from __future__ import annotations

import math

import numpy as np
import pytest

from vehicles.quadrotor_brush.control.estimator import (
    EstimatorConfig,
    MocapEstimator,
    steady_state_gain,
)
from vehicles.quadrotor_brush.control.inner import G_C, inner_setpoint
from vehicles.quadrotor_brush.control.tip import (
    body_reference_for_tip,
    lag_compensated,
    tip_filter_poles,
)

G = 9.81


def test_filter_is_stable() -> None:
    dt = 0.01
    f = np.array([[1.0, dt, 0.5 * dt**2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
    k = steady_state_gain(EstimatorConfig(), dt)
    closed = (np.eye(3) - np.outer(k, [1.0, 0.0, 0.0])) @ f
    assert np.max(np.abs(np.linalg.eigvals(closed))) < 1.0


def test_filter_recovers_velocity_and_a_constant_disturbance() -> None:
    """No command, constant push d, no drag: delayed exact positions of p0 + v0 t + d t^2 / 2."""
    config = EstimatorConfig(latency_s=0.005, drag_per_s=(0.0, 0.0, 0.0))
    d = np.array([[0.2, -0.1, 0.05]])
    v0 = np.array([[0.3, 0.0, -0.1]])
    est = MocapEstimator(config, 0.01, np.zeros((1, 3)))
    for k in range(1, 301):
        t_meas = k * 0.01 - config.latency_s
        est.update(v0 * t_meas + 0.5 * d * t_meas**2, np.zeros((1, 3)))
    t = 300 * 0.01
    assert est.velocity_mps_enu == pytest.approx(v0 + d * t, abs=1e-5)
    assert est.position_m_enu == pytest.approx(v0 * t + 0.5 * d * t**2, abs=1e-6)
    assert est.disturbance_mps2_enu == pytest.approx(d, abs=1e-4)


def test_g_c_maps_body_accelerations_to_attitude_and_throttle() -> None:
    accel = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    out = inner_setpoint(accel, np.zeros(4))
    assert out.pitch_rad == pytest.approx([0.1019, 0.0, 0.0, 0.0])  # +x: nose down (FLU +pitch)
    assert out.roll_rad == pytest.approx([0.0, -0.1019, 0.0, 0.0])  # +y: roll left (FLU -roll)
    hover = G_C[0, 2] * G
    assert out.throttle[2] == pytest.approx(hover)
    assert out.throttle[3] == pytest.approx(G_C[0, 2] * (G + 1.0))
    assert out.throttle[0] == pytest.approx(hover / math.cos(0.1019))


def test_yaw_rotates_the_command_into_the_body() -> None:
    out = inner_setpoint(np.array([[0.0, 1.0, 0.0]]), np.array([math.pi / 2]))
    assert out.pitch_rad[0] == pytest.approx(0.1019)  # north is the body's forward
    assert out.roll_rad[0] == pytest.approx(0.0, abs=1e-12)


def test_commands_are_clamped() -> None:
    out = inner_setpoint(np.array([[50.0, -50.0, 100.0]]), np.zeros(1), max_tilt_rad=0.5)
    assert abs(out.pitch_rad[0]) == pytest.approx(0.5)
    assert abs(out.roll_rad[0]) == pytest.approx(0.5)
    assert out.throttle[0] == pytest.approx(0.6553)


def test_tip_filter_poles_factor_the_inverse() -> None:
    lever, drag = 0.335, 0.35
    a, b = tip_filter_poles(lever, drag)
    tau2 = lever / G
    for s in (a * -1.0, b):  # roots of 1 - tau^2 (s^2 + c s)
        assert 1.0 - tau2 * (s * s + drag * s) == pytest.approx(0.0, abs=1e-9)


def test_body_reference_puts_the_tip_on_the_reference() -> None:
    """p - tau^2 (p'' + c p') = r for a smooth reference (interior, finite differences)."""
    dt, lever, drag = 0.01, 0.335, 0.35
    t = np.arange(0.0, 20.0, dt)
    bump = np.exp(-(((t - 10.0) / 1.5) ** 2))
    r = np.zeros((t.size, 3))
    r[:, 0] = 0.4 * bump
    r[:, 1] = 0.2 * bump * np.sin(t)
    v = np.gradient(r, dt, axis=0)
    acc = np.gradient(v, dt, axis=0)
    p, pv, _ = body_reference_for_tip(r, v, acc, dt, lever, G, (drag, drag))
    pdd = np.gradient(np.gradient(p, dt, axis=0), dt, axis=0)
    pd = np.gradient(p, dt, axis=0)
    tip = p - lever / G * (pdd + drag * pd)
    inner = slice(200, -200)
    assert np.max(np.abs(tip[inner, :2] - r[inner, :2])) < 2e-4
    assert np.array_equal(p[:, 2], r[:, 2])
    assert np.max(np.abs(pv[inner] - pd[inner])) < 2e-3  # velocities map consistently
    assert np.max(np.abs(p[inner, :2] - r[inner, :2])) > 0.005  # the body does move differently
    same = body_reference_for_tip(r, v, acc, dt, 0.0)
    assert same[0] is r


def test_lag_compensation_leads_a_sinusoid() -> None:
    dt, w = 0.01, 2.0
    t = np.arange(0.0, 10.0, dt)
    a = np.stack([np.sin(w * t)] * 3, axis=1)
    led = lag_compensated(a, dt, [0.06, 0.06, 0.02], [0.0016, 0.0016, 0.0])
    expected = np.sin(w * t) + 0.06 * w * np.cos(w * t) - 0.0016 * w * w * np.sin(w * t)
    assert led[10:-10, 0] == pytest.approx(expected[10:-10], abs=1e-3)
