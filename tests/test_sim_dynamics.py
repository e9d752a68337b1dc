"""The simulated quadrotor: inner loop, thrust limit, drag, ground effect, mocap, determinism."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from sim.errors import SimError
from sim.params import MocapParams, WindParams
from vehicles.quadrotor_brush.dynamics import InnerLoopCommand, ground_effect_gain
from vehicles.quadrotor_brush.params import QuadrotorParams, WorldParams
from vehicles.quadrotor_brush.world import World

G = 9.81
HIGH = (0.0, 0.0, 50.0)  # far above the board: no ground effect to speak of


def quiet(**changes: object) -> WorldParams:
    """No wind, no mocap noise or latency unless asked."""
    base = WorldParams(mocap=MocapParams(latency_s=0.0, noise_std_m=0.0))
    return dataclasses.replace(base, **changes)  # type: ignore[arg-type]


def command(
    world: World, *, roll: float = 0.0, pitch: float = 0.0, throttle=None
) -> InnerLoopCommand:  # type: ignore[no-untyped-def]
    n = world.n_vehicles
    thr = world.hover_throttle if throttle is None else np.full(n, throttle)
    return InnerLoopCommand(thr, np.full(n, roll), np.full(n, pitch), np.zeros(n))


def test_hover_throttle_holds_still() -> None:
    world = World(quiet(), [HIGH, (1.0, 2.0, 0.5)], seed=0)
    for _ in range(300):
        world.step(command(world))
    assert np.max(np.abs(world.state.position_m_enu - np.array([HIGH, (1.0, 2.0, 0.5)]))) < 1e-9
    assert np.max(np.abs(world.state.velocity_mps_enu)) < 1e-9


def test_pitch_accelerates_east_and_roll_accelerates_south() -> None:
    """FLU body: +pitch tilts the thrust to +x, +roll to -y; a = g tan(angle) when level thrust
    is kept (throttle / cos)."""
    params = quiet(quadrotor=QuadrotorParams(drag_n_per_mps=(0.0, 0.0, 0.0)))
    angle = 0.1
    for roll, pitch, axis, sign in ((0.0, angle, 0, 1.0), (angle, 0.0, 1, -1.0)):
        world = World(params, [HIGH], seed=0)
        thr = float(world.hover_throttle[0]) / math.cos(angle)
        for _ in range(50):  # attitude settles (25 rad/s)
            world.step(command(world, roll=roll, pitch=pitch, throttle=thr))
        v0 = world.state.velocity_mps_enu[0, axis]
        for _ in range(100):
            world.step(command(world, roll=roll, pitch=pitch, throttle=thr))
        accel = (world.state.velocity_mps_enu[0, axis] - v0) / 1.0
        assert accel == pytest.approx(sign * G * math.tan(angle), rel=2e-3)
        assert abs(world.state.velocity_mps_enu[0, 2]) < 5e-3  # only the tilt-up transient


def test_attitude_step_matches_second_order_response() -> None:
    """The exact discretisation reproduces the closed-form step response of the inner loop."""
    q = QuadrotorParams()
    world = World(quiet(quadrotor=q), [HIGH], seed=0)
    wn, zeta, step = q.attitude_natural_freq_radps, q.attitude_damping, 0.1
    wd = wn * math.sqrt(1.0 - zeta**2)
    for k in range(1, 11):
        world.step(command(world, pitch=step))
        t = k * 0.01
        expected = step * (
            1.0 - math.exp(-zeta * wn * t) * (math.cos(wd * t) + zeta * wn / wd * math.sin(wd * t))
        )
        assert world.state.attitude_rad[0, 1] == pytest.approx(expected, abs=1e-12)


def test_thrust_saturates_at_thrust_to_weight() -> None:
    world = World(quiet(), [HIGH], seed=0)
    thrust = []
    for _ in range(100):
        world.step(command(world, throttle=10.0))
        thrust.append(world.state.thrust_mps2[0])
    limit = QuadrotorParams().max_specific_thrust_mps2
    assert max(thrust) <= limit
    assert thrust[-1] == pytest.approx(limit, rel=1e-6)
    v0 = world.state.velocity_mps_enu[0, 2]
    world.step(command(world, throttle=10.0))
    accel = (world.state.velocity_mps_enu[0, 2] - v0) / 0.01
    drag = QuadrotorParams().drag_n_per_mps[2] / QuadrotorParams().mass_kg
    assert accel == pytest.approx(limit - G - drag * v0, rel=0.01)


def test_drag_carries_the_vehicle_downwind() -> None:
    """Level, with hover thrust, a vehicle drifts towards the wind speed with time constant m/D."""
    wind = WindParams(mean_mps_enu=(1.0, 0.0, 0.0))
    world = World(quiet(wind=wind), [HIGH], seed=0)
    for _ in range(100):
        world.step(command(world))
    tau = QuadrotorParams().mass_kg / QuadrotorParams().drag_n_per_mps[0]
    assert world.state.velocity_mps_enu[0, 0] == pytest.approx(1.0 - math.exp(-1.0 / tau), rel=1e-3)


def test_ground_effect_gain_and_offset_near_the_board() -> None:
    radius = 0.127
    gains = ground_effect_gain(np.array([radius, 4.0 * radius, 100.0]), radius)
    assert gains[0] == pytest.approx(1.0 / (1.0 - 1.0 / 16.0))
    assert gains[1] == pytest.approx(1.0 / (1.0 - 1.0 / 256.0))
    assert gains[2] == pytest.approx(1.0, abs=1e-6)
    # out-of-ground-effect hover throttle near the board makes the vehicle climb
    world = World(quiet(), [(0.0, 0.0, 0.3)], seed=0)
    oge = QuadrotorParams().throttle_per_mps2 * G
    assert world.hover_throttle[0] < oge
    for _ in range(50):
        world.step(command(world, throttle=oge))
    assert world.state.velocity_mps_enu[0, 2] > 0.02


def test_mocap_frame_is_delayed_by_the_latency() -> None:
    params = quiet(
        mocap=MocapParams(latency_s=0.005, noise_std_m=0.0),
        quadrotor=QuadrotorParams(drag_n_per_mps=(0.0, 0.0, 0.0)),
    )
    world = World(params, [HIGH], seed=0)
    world.state.velocity_mps_enu = np.array([[0.5, 0.0, 0.0]])
    for _ in range(5):
        world.step(command(world))
    frame = world.mocap_frame()
    assert world.time_s - frame.capture_time_s == pytest.approx(0.005)
    lag = world.state.position_m_enu[0, 0] - frame.position_m_enu[0, 0]
    assert lag == pytest.approx(0.5 * 0.005, rel=1e-9)


def test_mocap_noise_has_the_configured_spread() -> None:
    params = quiet(mocap=MocapParams(latency_s=0.0, noise_std_m=0.0002))
    world = World(params, np.tile(HIGH, (100, 1)), seed=3)
    errors = []
    for _ in range(20):
        errors.append(world.mocap_frame().position_m_enu - world.state.position_m_enu)
        world.step(command(world))
    assert np.std(np.array(errors)) == pytest.approx(0.0002, rel=0.05)


def test_gusts_have_the_configured_spread() -> None:
    wind = WindParams(mean_mps_enu=(1.0, 0.0, 0.0), gust_sigma_mps_enu=(0.3, 0.3, 0.1))
    world = World(quiet(wind=wind), np.tile(HIGH, (400, 1)), seed=5)
    for _ in range(50):
        world.step(command(world))
    gust = world.wind_mps_enu - np.array([1.0, 0.0, 0.0])
    assert np.std(gust, axis=0) == pytest.approx([0.3, 0.3, 0.1], rel=0.12)


def run_noisy(seed: int, n: int) -> tuple[np.ndarray, np.ndarray]:
    params = WorldParams(wind=WindParams.from_speed(1.0, gust_ratio=0.3, length_scale_m=1.0))
    world = World(params, np.tile((0.0, 0.0, 1.0), (n, 1)), seed=seed)
    frames = []
    for _ in range(120):
        frames.append(world.mocap_frame().position_m_enu)
        world.step(command(world))
    return world.state.position_m_enu, np.array(frames)


def test_same_seed_is_bit_identical_and_other_seeds_differ() -> None:
    a, fa = run_noisy(7, 3)
    b, fb = run_noisy(7, 3)
    c, _ = run_noisy(8, 3)
    assert np.array_equal(a, b) and np.array_equal(fa, fb)
    assert not np.array_equal(a, c)


def test_a_vehicles_noise_does_not_depend_on_the_fleet_size() -> None:
    _, alone = run_noisy(11, 1)
    _, fleet = run_noisy(11, 4)
    assert np.allclose(alone[:, 0], fleet[:, 0], rtol=0.0, atol=1e-12)


def test_invalid_parameters_name_the_field() -> None:
    with pytest.raises(SimError, match="thrust_to_weight"):
        QuadrotorParams(thrust_to_weight=0.9)
    with pytest.raises(SimError, match="initial_position"):
        World(WorldParams(), np.zeros((0, 3)), seed=0)
