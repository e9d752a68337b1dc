"""The closed loop: hover, wind rejection, writing quality, determinism, step-wise = batch."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from planner.samples import TrajectorySamples
from sim.params import MocapParams, WindParams
from sim.reference import writing_reference
from vehicles.quadrotor_brush.control.config import DEFAULT_CONFIG, PAPER_CONFIG
from vehicles.quadrotor_brush.flight import Flight, FlightLog, fly
from vehicles.quadrotor_brush.flight_config import FlightConfig
from vehicles.quadrotor_brush.metrics import flight_metrics
from vehicles.quadrotor_brush.params import WorldParams
from vehicles.quadrotor_brush.trace import flown_of

QUIET = WorldParams(mocap=MocapParams(noise_std_m=0.0))


def samples(**kwargs: object) -> TrajectorySamples:
    r = writing_reference(**kwargs)  # type: ignore[arg-type]
    return TrajectorySamples(
        r.t_s, r.position_m_enu, r.velocity_mps_enu, r.acceleration_mps2_enu, r.pen_down
    )


def hover(duration_s: float, height_m: float = 0.5) -> TrajectorySamples:
    t = np.arange(int(duration_s * 100) + 1) * 0.01
    p = np.tile([0.1, -0.2, height_m], (t.size, 1))
    z = np.zeros_like(p)
    return TrajectorySamples(t, p, z, z, np.zeros(t.size, dtype=bool))


def test_hover_is_an_equilibrium_at_hover_throttle() -> None:
    """Out of ground effect the loop starts in equilibrium: nothing moves, not even by a micron."""
    flight = Flight([hover(5.0, 30.0)], FlightConfig(world=QUIET, preroll_s=0.0))
    log = flight.run()
    drift = np.abs(log.position_m_enu[:, 0] - [0.1, -0.2, 30.0])
    assert drift.max() < 1e-6
    assert log.throttle[-1, 0] == pytest.approx(flight.world.hover_throttle[0], rel=1e-6)


def test_hover_over_the_board_settles_at_the_ground_effect_throttle() -> None:
    flight = Flight([hover(3.0, 0.335)], FlightConfig(world=QUIET))
    log = flight.run()
    error = np.abs(log.position_m_enu[:, 0] - [0.1, -0.2, 0.335])
    assert error.max() < 3e-4  # the integral still unwinds the climb of the first instants
    assert error[-1].max() < 5e-5
    hover_throttle = flight.world.hover_throttle[0]
    assert hover_throttle < QUIET.quadrotor.throttle_per_mps2 * 9.81  # ground effect helps
    assert log.throttle[-1, 0] == pytest.approx(hover_throttle, rel=1e-4)


@pytest.mark.parametrize(("config", "duration_s"), [(DEFAULT_CONFIG, 15.0), (PAPER_CONFIG, 60.0)])
def test_steady_wind_leaves_no_steady_error(config: object, duration_s: float) -> None:
    world = dataclasses.replace(QUIET, wind=WindParams(mean_mps_enu=(0.6, -0.4, 0.0)))
    log = fly([hover(duration_s, 0.335)], FlightConfig(world=world, controller=config))  # type: ignore[arg-type]
    target = log.reference_position_m_enu[-1, 0]
    tilt = log.body_z_enu[-1, 0, :2]
    assert np.dot(tilt, [0.6, -0.4]) < 0.0  # leaning into the wind
    if config is PAPER_CONFIG:  # the body holds; its brush, leaning, writes downwind
        assert np.max(np.abs(log.position_m_enu[-1, 0] - target)) < 2e-4
        assert np.dot(log.writing_point_error()[-1, 0, :2], [0.6, -0.4]) > 0.005
    else:  # the brush holds; the body stands upwind of it
        assert np.max(np.abs(log.writing_point_error()[-1, 0])) < 2e-4


def test_thrust_limit_holds_on_an_impossible_climb() -> None:
    t = np.arange(301) * 0.01
    p = np.zeros((t.size, 3))
    p[:, 2] = np.where(t < 0.5, 1.0, 20.0)
    z = np.zeros_like(p)
    ref = TrajectorySamples(t, p, z, z, np.zeros(t.size, dtype=bool))
    log = fly([ref], FlightConfig(world=QUIET, preroll_s=0.0))
    limit = QUIET.quadrotor.max_specific_thrust_mps2
    assert log.thrust_mps2.max() <= limit
    assert log.thrust_mps2.max() > 0.99 * limit


WRITE = {"shape": "circle", "size_m": 0.5, "writing_time_s": 5.0, "hold_s": 0.3}


def windy(seed_world: WorldParams | None = None) -> FlightConfig:
    world = WorldParams(wind=WindParams.from_speed(1.0, heading_rad=0.7))
    return FlightConfig(world=seed_world or world)


def test_default_controller_writes_a_circle_in_wind() -> None:
    config = windy()
    paper = dataclasses.replace(config, controller=PAPER_CONFIG)
    ref = samples(**WRITE)
    brush = config.world.brush
    shipped = flight_metrics(flown_of(fly([ref], config, seed=2)), brush, ref)
    published = flight_metrics(flown_of(fly([ref], paper, seed=2)), brush, ref)
    assert shipped.rmse_pen_down_m is not None and published.rmse_pen_down_m is not None
    assert shipped.rmse_pen_down_m < 0.005
    assert shipped.iou > 0.8
    assert shipped.rmse_pen_down_z_m is not None and shipped.rmse_pen_down_z_m < 0.002
    assert published.rmse_pen_down_m > 3.0 * shipped.rmse_pen_down_m
    assert published.iou < shipped.iou


def logs_equal(a: FlightLog, b: FlightLog) -> bool:
    fields = [f.name for f in dataclasses.fields(FlightLog)]
    return all(
        np.array_equal(getattr(a, name), getattr(b, name)) for name in fields if name != "t_s"
    )


def test_same_seed_is_bit_identical_and_another_differs() -> None:
    refs = [samples(**WRITE), samples(**{**WRITE, "shape": "figure8"})]
    config = windy()
    a, b, c = (fly(refs, config, seed=s) for s in (4, 4, 5))
    assert logs_equal(a, b)
    assert not np.array_equal(a.position_m_enu, c.position_m_enu)


def test_step_wise_flight_equals_the_batch() -> None:
    ref = samples(**WRITE)
    config = windy()
    batch = fly([ref], config, seed=3)
    flight = Flight([ref], config, seed=3, start_time_s=1000.0)
    states = []
    k = 0
    while not flight.done:
        k += 1
        # a jittery clock: sometimes late by a few ticks, never early
        late = 3 if k % 50 == 0 else 0
        states.append(flight.step(1000.0 + (k + late) * 0.01 + 0.001))
        k += late
    stepped = flight.log()
    assert logs_equal(batch, stepped)
    assert states[-1].done
    assert states[-1].time_s == pytest.approx(stepped.t_s[-1] + 0.01)
    assert stepped.t_s[0] == pytest.approx(1000.0)
    assert flight.step(0.0).time_s == states[-1].time_s  # the past is a no-op


def test_flight_state_reports_what_telemetry_needs() -> None:
    flight = Flight([samples(**WRITE), hover(2.0)], windy(), seed=0)
    state = flight.step(2.0)
    assert state.position_m_enu.shape == (2, 3)
    assert state.pen_down.dtype == np.bool_
    assert state.brush.contact.shape == (2,)
    assert not state.done
