"""Vehicle backends against the protocol: the simulator's autopilot modes, the ideal vehicle."""

from __future__ import annotations

import asyncio
import math

import numpy as np
import pytest

from vehicle_agent.backends.base import BackendError, Setpoint, VehicleBackend
from vehicle_agent.backends.kinematic import KinematicBackend
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.clock import TickClock
from vehicle_agent.motion import plan_move
from vehicles.registry import vehicle_kind

HOME = (0.0, -1.2, 0.0)


def fly_until(vehicle: SimVehicle, setpoint: Setpoint | None, done, max_s: float = 20.0):  # type: ignore[no-untyped-def]
    snaps = []
    while True:
        snap = vehicle.tick(setpoint)
        snaps.append(snap)
        if done(snap):
            return snaps
        assert snap.t_s < max_s, f"stuck in {snap.mode} at {snap.position_m_enu}"


def test_both_backends_satisfy_the_protocol() -> None:
    assert isinstance(KinematicBackend(HOME), VehicleBackend)
    assert isinstance(SimBackend(SimVehicle(HOME)), VehicleBackend)


def test_sim_vehicle_rests_on_the_ground_until_take_off() -> None:
    vehicle = SimVehicle(HOME)
    for _ in range(100):
        snap = vehicle.tick(None)
    assert snap.on_ground and not snap.armed and snap.mode == "idle"
    assert snap.position_m_enu == HOME and snap.t_s == pytest.approx(1.0)
    with pytest.raises(BackendError):
        vehicle.tick(Setpoint(position_m_enu=(0.0, 0.0, 1.0)))


def test_sim_vehicle_takes_off_holds_tracks_and_lands() -> None:
    vehicle = SimVehicle(HOME)
    vehicle.takeoff((0.0, -1.2, 1.0))
    snaps = fly_until(vehicle, None, lambda s: s.mode == "hold")
    assert math.dist(snaps[-1].position_m_enu, (0.0, -1.2, 1.0)) < 0.03
    heights = [s.position_m_enu[2] for s in snaps]
    assert min(heights) > -0.02 and max(heights) < 1.05  # no dip below ground, small overshoot
    move = plan_move((0.0, -1.2, 1.0), (0.5, -1.0, 1.0), vehicle.t_s, v_max_mps=0.6, a_max_mps2=0.8)
    errors = []
    while not move.done(vehicle.t_s - 1.0):
        target = move.setpoint(vehicle.t_s)
        snap = vehicle.tick(target)
        errors.append(math.dist(snap.position_m_enu, target.position_m_enu))
    assert snap.mode == "offboard" and max(errors) < 0.05 and errors[-1] < 0.01
    snap = vehicle.tick(None)
    assert snap.mode == "hold"
    vehicle.land()
    snaps = fly_until(vehicle, None, lambda s: s.mode == "idle")
    assert snaps[-1].on_ground and snaps[-1].position_m_enu[2] == HOME[2]
    assert math.dist(snaps[-1].position_m_enu[:2], (0.5, -1.0)) < 0.03


def test_sim_vehicle_brush_touches_only_over_the_board() -> None:
    def over_board(p: tuple[float, float, float]) -> bool:
        return abs(p[0]) <= 0.7 and abs(p[1]) <= 0.7

    vehicle = SimVehicle(HOME, contact_region=over_board)
    vehicle.takeoff((0.0, -1.2, 0.2))  # low: the world's board plane is at z = 0
    snaps = fly_until(vehicle, None, lambda s: s.mode == "hold")
    assert not any(s.pen_contact for s in snaps)
    free = SimVehicle(HOME)
    free.takeoff((0.0, -1.2, 0.2))
    snaps = fly_until(free, None, lambda s: s.mode == "hold")
    assert snaps[-1].pen_contact and snaps[-1].pen_width_m > 0.0


def test_estop_drops_the_vehicle_where_it_is() -> None:
    vehicle = SimVehicle(HOME)
    vehicle.takeoff((0.0, -1.2, 1.0))
    fly_until(vehicle, None, lambda s: s.position_m_enu[2] > 0.5)
    vehicle.estop()
    snap = vehicle.tick(None)
    assert snap.mode == "estop" and snap.on_ground and not snap.armed
    with pytest.raises(BackendError):
        vehicle.takeoff((0.0, -1.2, 1.0))


def test_async_wrapper_ticks_one_period() -> None:
    async def scenario() -> list[float]:
        backend = SimBackend(SimVehicle(HOME))
        first = await backend.start()
        await backend.takeoff((0.0, -1.2, 1.0))
        later = await backend.tick(None, 0.0)
        await backend.close()
        return [first.t_s, later.t_s, backend.control_period_s]

    assert asyncio.run(scenario()) == pytest.approx([0.0, 0.01, 0.01])


def test_tick_clock_paces_lock_step_and_skips_only_when_asked() -> None:
    wall = [100.0]
    clock = TickClock(period_s=0.01, time_scale=5.0, wall_s=lambda: wall[0])
    assert clock.delay_s() == 0.0 and clock.wall_period_s == pytest.approx(0.002)
    clock.advance()
    assert clock.delay_s() == pytest.approx(0.002) and clock.now_s == pytest.approx(0.01)
    wall[0] += 1.0  # a one-second stall: a simulated vehicle runs every missed tick
    clock.advance()
    assert clock.tick == 2 and clock.delay_s() == 0.0
    real = TickClock(period_s=0.01, skip_when_late=True, wall_s=lambda: wall[0])
    wall[0] += 0.5
    real.advance()
    assert real.tick == pytest.approx(50, abs=1) and real.delay_s() <= 0.01
    assert np.isclose(real.now_s, real.tick * 0.01)


def test_a_ground_kind_starts_and_stops_where_it_stands_and_drives_on_the_floor() -> None:
    kind = vehicle_kind("omni-wheel")
    home = (0.5, -1.0, 0.0)
    vehicle = SimVehicle(home, kind=kind, settings=kind.settings(None, None))
    assert not vehicle.airborne
    vehicle.takeoff((0.5, -1.0, 1.0))  # the hover height means nothing on the floor
    first = vehicle.tick(None)
    assert first.mode == "hold" and not first.on_ground and first.armed
    for _ in range(100):  # 1 s towards a point 5 cm ahead, the marker up
        snap = vehicle.tick(Setpoint(position_m_enu=(0.55, -1.0, 0.0)))
    assert abs(snap.position_m_enu[2]) < 1e-3 and snap.position_m_enu[0] > 0.52
    assert snap.pen_contact is False and snap.force_n is None
    vehicle.land()
    landed = vehicle.tick(None)
    assert landed.mode == "idle" and landed.on_ground
    assert math.dist(landed.position_m_enu, snap.position_m_enu) < 0.01  # rests where it stopped
