"""Simulated vehicles stepped together (a fleet host) fly exactly as each would alone."""

from __future__ import annotations

import asyncio
import math

import numpy as np

from sim.noise import NormalBlocks
from vehicle_agent.backends.base import Setpoint, VehicleSnapshot
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.backends.sim_round import StepRound, StepRounds
from vehicles.kind import LiveReference, LiveState
from vehicles.quadrotor_brush.loop import QuadrotorFleet
from vehicles.registry import vehicle_kind

KIND = vehicle_kind("quadrotor-brush")
SETTINGS = KIND.settings(None, None)
STARTS = [(0.0, 0.0, 1.2), (1.0, 2.0, 1.1), (-1.0, 0.5, 1.3)]


def reference(vehicle: int, tick: int) -> LiveReference:
    x, y, z = STARTS[vehicle]
    return LiveReference(
        (x + 0.1 * math.sin(0.01 * tick), y, z - 0.0005 * tick), (0.01, 0.0, 0.0), (0.0, 0.02, 0.0)
    )


def alone(vehicle: int, first: int, end: int) -> list[LiveState]:
    live = KIND.simulated_vehicle(STARTS[vehicle], SETTINGS, seed=10 + vehicle)
    states = []
    for tick in range(first, end):
        live.step(reference(vehicle, tick))
        states.append(live.state())
    return states


def test_vehicles_joining_leaving_and_late_fly_in_a_fleet_exactly_as_alone() -> None:
    joins, leaves = (0, 7, 150), (400, 500, 300)
    fleet = QuadrotorFleet(SETTINGS.flight.world, SETTINGS.flight.controller)
    members = {}
    flown: list[list[LiveState]] = [[], [], []]
    for tick in range(500):
        for i in range(3):
            if tick == joins[i]:
                members[i] = fleet.vehicle(STARTS[i], seed=10 + i)
            if tick == leaves[i]:
                fleet.release(members.pop(i))
        late = 2 in members and tick % 2 == 1  # its tick in a round of its own
        for i, member in members.items():
            if not (late and i == 2):
                member.step(reference(i, tick))
        fleet.step()
        if late:
            members[2].step(reference(2, tick))
            fleet.step()
        for i, member in members.items():
            flown[i].append(member.state())
    assert len(fleet) == 1
    for i in range(3):
        assert flown[i] == alone(i, joins[i], leaves[i])  # bit for bit


def test_noise_streams_keep_their_numbers_when_taken_apart_and_stacked() -> None:
    together = NormalBlocks(3, 2, stream=1, block=10)
    expected = [together.draw() for _ in range(25)]
    first = NormalBlocks(3, 1, stream=1, block=10)  # vehicle 0 alone
    second = NormalBlocks(3, 2, stream=1, block=10).take([1])  # vehicle 1 taken out
    for _ in range(4):
        first.draw()
    for _ in range(3):
        second.draw()
    merged = NormalBlocks.stack([first, second])  # mid-block: 6 and 7 draws left
    got = [merged.draw() for _ in range(21)]
    np.testing.assert_array_equal([g[0] for g in got], [e[0] for e in expected[4:25]])
    np.testing.assert_array_equal([g[1] for g in got], [e[1] for e in expected[3:24]])


async def fly_three(
    rounds: StepRounds | None, offsets: tuple[int, ...] = (0, 0, 0)
) -> list[list[VehicleSnapshot]]:
    """Three simulated vehicles' backends ticking concurrently: take-off, hold, a setpoint;
    each starts ``offsets`` turns of the event loop late and yields a turn between its ticks
    (as vehicles behind the wall clock do)."""
    backends = []
    for i, home in enumerate(STARTS):
        step_round = None if rounds is None else rounds.round_for(KIND, SETTINGS)
        fleet = None if step_round is None else step_round.fleet
        backends.append(SimBackend(SimVehicle(home, seed=i, fleet=fleet), step_round))
    for backend, (x, y, z) in zip(backends, STARTS, strict=True):
        await backend.takeoff((x, y, z + 0.5))
    snaps: list[list[VehicleSnapshot]] = [[] for _ in backends]

    async def loop(i: int) -> None:
        for _ in range(offsets[i]):
            await asyncio.sleep(0)
        for tick in range(300):
            await asyncio.sleep(0)
            setpoint = Setpoint(position_m_enu=(0.1 * i, 0.0, 1.5)) if tick > 250 else None
            snaps[i].append(await backends[i].tick(setpoint, 0.0))

    await asyncio.gather(*(loop(i) for i in range(len(backends))))
    for backend in backends:
        await backend.close()
    return snaps


def test_a_round_steps_the_fleet_once_for_every_vehicle_ticking_in_it() -> None:
    rounds = StepRounds()
    together = asyncio.run(fly_three(rounds))
    assert together == asyncio.run(fly_three(None))
    step_round = rounds.round_for(KIND, SETTINGS)
    assert isinstance(step_round, StepRound)
    assert step_round.steps == 300  # one fleet step per turn for the three vehicles
    assert isinstance(step_round.fleet, QuadrotorFleet) and len(step_round.fleet) == 0


def test_vehicles_ticking_a_turn_apart_fall_into_one_round() -> None:
    rounds = StepRounds()
    together = asyncio.run(fly_three(rounds, offsets=(0, 1, 2)))
    assert together == asyncio.run(fly_three(None, offsets=(0, 1, 2)))
    step_round = rounds.round_for(KIND, SETTINGS)
    assert isinstance(step_round, StepRound)
    assert step_round.steps <= 302  # 900 vehicle-ticks: all three in one round after the first
