"""The wall writer's estimators: the attitude filter, the pen-spring observer of the normal and
the disturbance observer of the wind."""

from __future__ import annotations

import numpy as np
import pytest

from vehicles.hexarotor_sponge.attitude_filter import AttitudeFilter
from vehicles.hexarotor_sponge.disturbance_observer import DisturbanceObserver
from vehicles.hexarotor_sponge.normal_observer import NormalObserver
from vehicles.hexarotor_sponge.params import HexarotorParams
from vehicles.hexarotor_sponge.rotations import rotation_of


def _angle_rad(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.arccos(np.clip((np.trace(a.T @ b) - 1.0) / 2.0, -1.0, 1.0)))


def test_attitude_filter_follows_the_gyro_and_drops_the_mocap_noise() -> None:
    """Turning at 0.2 rad/s about a tilted axis, with 3 mrad of noise on every attitude reading:
    after 3 s the filtered attitude is within 1 mrad of the truth (the raw reading 3-5 mrad)."""
    rng = np.random.default_rng(1)
    dt = 0.01
    omega = np.array([0.05, -0.1, 0.2])
    filt = AttitudeFilter(dt)
    truth = np.eye(3)
    errors, raw = [], []
    for k in range(300):
        truth = truth @ rotation_of(omega * dt)
        measured = truth @ rotation_of(3e-3 * rng.standard_normal(3))
        estimate = filt.update(measured, omega)
        if k >= 200:
            errors.append(_angle_rad(estimate, truth))
            raw.append(_angle_rad(measured, truth))
    assert max(errors) < 1e-3
    assert np.sqrt(np.mean(np.square(errors))) < 0.2 * np.sqrt(np.mean(np.square(raw)))


def test_normal_observer_reads_the_tip_off_the_pen_spring() -> None:
    """Pressed at 3 N and holding still, with mocap 2 mm off and noisy: the observer puts the
    nominal tip at the spring's compression (3 N - 0.5 N preload) / 400 N/m = 6.25 mm into the
    wall, to 0.2 mm, and the velocity near 0; off the wall (0.1 N) it keeps to the mocap."""
    params = HexarotorParams()
    obs = NormalObserver(params, 0.01)
    rng = np.random.default_rng(2)
    for _ in range(300):
        force = 3.0 + 0.05 * rng.standard_normal()
        p, v = obs.update(-6.25e-3 + 2e-3 + 1e-3 * rng.standard_normal(), 0.0, force, 0.0)
    assert p == pytest.approx(-6.25e-3, abs=0.2e-3)
    assert abs(v) < 2e-3
    assert obs.touching
    assert obs.contact_position_m(0.4) == 0.0


def test_normal_observer_tells_a_touch_from_noise_and_a_glitch() -> None:
    """The touch flips after three readings in a row beyond 2.5 sigma (0.125 N): the world's
    first F/T reading (0.53 N, one tick) is no touch, nor 20 s of free flight's 0.05 N noise;
    a landing at 0.15 N is one from its third reading (the single reading above 0.25 N it
    replaced missed it), a press at 0.25 N in that noise stays one, and a lift-off ends it
    after three readings of nothing."""
    params = HexarotorParams()
    obs = NormalObserver(params, 0.01)
    rng = np.random.default_rng(3)

    def read(force_n: float) -> bool:
        obs.update(0.0, 0.0, force_n, 0.0)
        return obs.touching

    assert not any(read(f) for f in [0.53, 0.0, 0.0, 0.0])
    assert not any(read(0.05 * rng.standard_normal()) for _ in range(2000))
    landing = [read(0.15) for _ in range(3)]
    assert landing == [False, False, True]
    assert all(read(0.25 + 0.05 * rng.standard_normal()) for _ in range(1000))
    lift_off = [read(0.0) for _ in range(3)]
    assert lift_off == [True, True, False]


def test_disturbance_observer_finds_a_steady_push_behind_a_late_noisy_mocap() -> None:
    """A 3.2 kg body pushed by an unknown (0.3, -0.2, 0.1) N while its known forces wave it
    about, seen through motion capture 10 ms late with 1 mm and 5 mm/s of noise: over the
    fourth second the estimate is within 0.015 N of the push on every axis on average
    (measured at most 0.004 N) and scatters by under 0.07 N RMS (measured 0.04-0.055 N; a
    finite difference of the velocity readings, 5 mm/s over 10 ms on 3.2 kg, scatters by
    2.3 N)."""
    rng = np.random.default_rng(2)
    dt, mass = 0.01, 3.2
    push = np.array([0.3, -0.2, 0.1])
    observer = DisturbanceObserver(mass, dt)
    p, v = np.zeros(3), np.zeros(3)
    readings = [(p.copy(), v.copy())]
    estimates = []
    for k in range(400):
        known = np.array([0.5, -0.3, 0.2]) * np.sin(np.array([1.0, 2.0, 3.0]) * k * dt)
        a = known + push / mass  # over this period; the observer hears of it at its end
        p, v = p + v * dt + 0.5 * a * dt**2, v + a * dt
        readings.append((p.copy(), v.copy()))
        late_p, late_v = readings.pop(0)  # motion capture: the state one period ago
        noisy_p = late_p + 1e-3 * rng.standard_normal(3)
        noisy_v = late_v + 5e-3 * rng.standard_normal(3)
        estimates.append(observer.update(noisy_p, noisy_v, known))
    error_n = np.array(estimates[300:]) - push
    assert np.abs(error_n.mean(axis=0)).max() < 0.015
    assert np.sqrt(np.mean(error_n**2, axis=0)).max() < 0.07
