"""The hexarotor in its MuJoCo world under the hybrid motion-force controller."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from planner.samples import TrajectorySamples
from vehicles.hexarotor_sponge.controller import FRICTION_EPS_MPS, HybridController, Reference
from vehicles.hexarotor_sponge.flight import fly_plan
from vehicles.hexarotor_sponge.fly_settings import CALM, FlySettings, WorldNoise
from vehicles.hexarotor_sponge.params import GRAVITY_MPS2, HexarotorParams
from vehicles.hexarotor_sponge.world import Measurement, facing_rotation
from vehicles.kind import StrokeInput, WritingPlan
from vehicles.surface import Surface

SURFACE = Surface.of("vertical", (1.0, 3.0, 2.0), 0.3)


def _plan(t_s: np.ndarray, xy_m: np.ndarray, force_n: np.ndarray) -> WritingPlan:
    """A hand-made reference on the wall (positions at the wall, given forces)."""
    pos = SURFACE.to_world(xy_m, 0.0)
    vel = np.gradient(pos, t_s, axis=0)
    samples = TrajectorySamples(t_s, pos, vel, np.zeros_like(pos), force_n > 0.0)
    strokes = (StrokeInput(np.array([[0.0, 0.0], [0.01, 0.0]])),)
    return WritingPlan(samples, strokes, SURFACE, force_n=force_n)


@pytest.mark.slow
def test_holds_a_constant_force_on_a_static_wall() -> None:
    t = np.arange(0.0, 5.0, 0.01)
    force = np.clip(2.0 * t, 0.0, 3.0)
    flown = fly_plan(_plan(t, np.zeros((t.size, 2)), force), FlySettings(noise=WorldNoise()))
    assert flown.force_n is not None
    hold = t > 2.5
    assert np.mean(flown.force_n[hold]) == pytest.approx(3.0, abs=0.05)
    assert np.std(flown.force_n[hold]) < 0.15
    estimate = flown.extra["force_estimate_n"][hold]
    assert np.mean(estimate) == pytest.approx(3.0, abs=0.05)
    tip_on_wall = SURFACE.to_local(flown.writing_point_m_enu[hold])
    assert np.abs(tip_on_wall[:, :2]).max() < 0.01
    assert np.abs(tip_on_wall[:, 2]).max() < 2e-3
    # The reference starts on the wall at 0 N: the pen touches it at most lightly (measured
    # 0.06 N, a 0.3 mm hairline, with the disturbance observer holding the tip on the wall;
    # 0 N without it, the tip 0.01 mm off).
    assert flown.force_n[0] < 0.1
    assert flown.ink_width_m[0] < 0.5e-3


@pytest.mark.slow
def test_contact_model_compensates_sliding_friction() -> None:
    t = np.arange(0.0, 6.0, 0.01)
    x = np.where(t > 2.0, 0.1 * (t - 2.0), 0.0)
    xy = np.column_stack([x, np.zeros_like(x)])
    force = np.clip(2.0 * t, 0.0, 2.5)
    plan = _plan(t, xy, force)
    ours = fly_plan(plan, FlySettings(noise=CALM))
    baseline = fly_plan(plan, FlySettings(noise=CALM, contact_model=False))
    sliding = t > 3.0
    err_ours = np.linalg.norm(ours.writing_point_m_enu - ours.reference_m_enu, axis=1)[sliding]
    err_base = np.linalg.norm(baseline.writing_point_m_enu - baseline.reference_m_enu, axis=1)
    assert np.sqrt(np.mean(err_ours**2)) < 0.5 * np.sqrt(np.mean(err_base[sliding] ** 2))
    assert ours.force_n is not None
    assert np.mean(ours.force_n[sliding]) == pytest.approx(2.5, abs=0.15)


def test_contact_aware_loop_compensates_slow_sliding_friction() -> None:
    """Pressed at 3 N and sliding at 2.5 cm/s (how fast the pen moves while its force ramps at
    the planner's 2 N/s): the wall's friction is Coulomb's, full mu F, and the contact-aware loop
    compensates it all (friction smoothed below 3 mm/s), so the tip keeps within 1 mm of the
    reference along the stroke (measured 0.43 mm RMS; smoothed below 3 cm/s, as the planner's
    model is, it lagged 3.3 mm RMS, 4.8 mm at worst)."""
    assert FRICTION_EPS_MPS < 0.01
    t = np.arange(0.0, 6.0, 0.01)
    x = np.where(t > 2.0, 0.025 * (t - 2.0), 0.0)
    plan = _plan(t, np.column_stack([x, np.zeros_like(x)]), np.clip(2.0 * t, 0.0, 3.0))
    flown = fly_plan(plan, FlySettings(noise=CALM))
    along_m = (
        SURFACE.to_local(flown.writing_point_m_enu) - SURFACE.to_local(plan.samples.position_m_enu)
    )[:, 0]
    sliding = t > 3.0
    assert np.sqrt(np.mean(along_m[sliding] ** 2)) < 1e-3


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_disturbance_observer_cancels_the_wind(seed: int) -> None:
    """A vertical stroke pressed at 2.5 N in 1 m/s of wind along the wall with 0.3 m/s gusts
    (no sensor noise): with the disturbance observer the tip keeps across the stroke within a
    third of the paper's motion control's error and under 0.4 mm RMS (measured 0.10-0.18 mm
    against 0.85-1.06 mm for seeds 0-2)."""
    wind = replace(CALM, wind_mps=1.0, gust_mps=0.3)
    t = np.arange(0.0, 5.0, 0.01)
    y = np.where(t > 1.0, 0.1 * (t - 1.0), 0.0)
    plan = _plan(t, np.column_stack([np.zeros_like(y), y]), np.clip(2.0 * t, 0.0, 2.5))
    across_rms_m = {}
    for observer in (True, False):
        settings = FlySettings(noise=wind, disturbance_observer=observer)
        flown = fly_plan(plan, settings, seed=seed)
        local = SURFACE.to_local(flown.writing_point_m_enu)
        across_m = (local - SURFACE.to_local(plan.samples.position_m_enu))[t > 1.5, 0]
        across_rms_m[observer] = np.sqrt(np.mean(across_m**2))
    assert across_rms_m[True] < min(0.4e-3, across_rms_m[False] / 3.0)


@pytest.mark.slow
def test_sliding_sponge_does_not_chatter() -> None:
    """The contact force of the sponge sliding at 10 cm/s is smooth: what is left after a 0.1 s
    moving average stays under 0.05 N (with MuJoCo's default contact impedance it chattered at
    20 Hz on the 2 ms physics step: 0.34 N)."""
    t = np.arange(0.0, 6.0, 0.01)
    x = np.where(t > 2.0, 0.1 * (t - 2.0), 0.0)
    force = np.clip(2.0 * t, 0.0, 2.5)
    plan = _plan(t, np.column_stack([x, np.zeros_like(x)]), force)
    flown = fly_plan(plan, FlySettings(noise=CALM))
    assert flown.force_n is not None
    sliding = (t > 3.0) & (t < 5.9)
    smooth = np.convolve(flown.force_n, np.ones(10) / 10, mode="same")
    assert np.sqrt(np.mean((flown.force_n - smooth)[sliding] ** 2)) < 0.05


@pytest.mark.parametrize("speed_mps", [0.0, 0.02, 0.2])
def test_fused_force_estimate_is_unbiased_by_friction(speed_mps: float) -> None:
    """The F/T reading (force and moment at the sensor) of 3 N pressed with the wall's Coulomb
    friction (mu F against the sliding direction while sliding, a static 0.5 N at rest) gives
    3 N at every speed of the reference (the unweighted fit of the smoothed contact model read
    3.13 N at 2 cm/s). The vehicle holds still: the last command balanced weight and contact."""
    params = HexarotorParams()
    ctrl = HybridController(params, SURFACE, dt_s=0.01)
    rot = facing_rotation(SURFACE)
    along = np.asarray(SURFACE.x_axis_enu)
    friction = params.wall_friction * 3.0 if speed_mps > 0.0 else 0.5
    contact = 3.0 * np.asarray(SURFACE.normal_enu) - friction * along
    weight = (params.arm_mass_kg + params.pen_mass_kg) * np.array([0.0, 0.0, -GRAVITY_MPS2])
    ctrl.last_command_n_enu = -contact - params.mass_kg * np.array([0.0, 0.0, -GRAVITY_MPS2])
    meas = Measurement(
        base_m_enu=np.zeros(3),
        velocity_mps_enu=speed_mps * along,
        rotation_body_to_enu=rot,
        omega_radps_body=np.zeros(3),
        ft_force_n_sensor=rot.T @ (contact + weight),
        ft_torque_nm_sensor=np.cross([params.arm_length_m, 0.0, 0.0], rot.T @ contact)
        + np.cross(params.arm_com_m_sensor, rot.T @ weight),
    )
    ref = Reference(np.zeros(3), speed_mps * along, np.zeros(3), 3.0)
    assert ctrl.estimate_force_n(meas, ref) == pytest.approx(3.0, abs=1e-9)


@pytest.mark.parametrize("contact_model", [True, False])
def test_force_estimate_takes_the_arm_inertia_out(contact_model: bool) -> None:
    """Off the wall, accelerating at 0.3 m/s^2 into it and 0.2 m/s^2 along it while sliding
    (the command m (a - g) did it): the F/T sensor reads the arm and pen's inertia, -0.28 kg
    times the acceleration; the contact-aware estimate reads no contact, the control baseline's
    bare axis 0.084 N, as if the pen pressed."""
    params = HexarotorParams()
    ctrl = HybridController(params, SURFACE, dt_s=0.01, contact_model=contact_model)
    rot = facing_rotation(SURFACE)
    normal, along = np.asarray(SURFACE.normal_enu), np.asarray(SURFACE.x_axis_enu)
    gravity = np.array([0.0, 0.0, -GRAVITY_MPS2])
    accel = -0.3 * normal + 0.2 * along
    ctrl.last_command_n_enu = params.mass_kg * (accel - gravity)
    arm_kg = params.arm_mass_kg + params.pen_mass_kg
    meas = Measurement(
        base_m_enu=np.zeros(3),
        velocity_mps_enu=0.1 * along,
        rotation_body_to_enu=rot,
        omega_radps_body=np.zeros(3),
        ft_force_n_sensor=rot.T @ (arm_kg * (gravity - accel)),
        ft_torque_nm_sensor=np.zeros(3),
    )
    ref = Reference(np.zeros(3), 0.1 * along, np.zeros(3), 0.0)
    expected = 0.0 if contact_model else arm_kg * 0.3
    assert ctrl.estimate_force_n(meas, ref) == pytest.approx(expected, abs=1e-9)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_contact_aware_force_loop_beats_the_control_baseline(seed: int) -> None:
    """A short stroke in wind and sensor noise, the force rising and falling at 1-2 N/s while
    the pen slides at 10 cm/s: the contact-aware loop (the pen's compression rate fed forward,
    the tip's normal position read off the pen's spring) holds the force with an RMSE at least
    30 % below the control baseline's (measured 0.55 / 0.64 / 0.58 of it for seeds 0-2, both
    loops with the disturbance observer; 0.64 / 0.65 / 0.59 before the arm's inertia left the
    force estimate and the landing the force integral)."""
    t = np.arange(0.0, 4.0, 0.01)
    x = np.where(t > 0.5, 0.1 * (t - 0.5), 0.0)
    force = np.interp(t, [0.0, 1.5, 2.5, 3.5, 4.0], [0.0, 3.0, 2.0, 3.0, 2.0])
    plan = _plan(t, np.column_stack([x, np.zeros_like(x)]), force)
    rmse = {}
    for contact_model in (True, False):
        settings = FlySettings(noise=WorldNoise(), contact_model=contact_model)
        flown = fly_plan(plan, settings, seed=seed)
        assert flown.force_n is not None
        rmse[contact_model] = np.sqrt(np.mean((flown.force_n - force)[force > 0.0] ** 2))
    assert rmse[True] <= 0.7 * rmse[False]
