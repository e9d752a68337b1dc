"""When a vehicle's loop may rest (pure), and the clock that catches up after a rest."""

from __future__ import annotations

from dataclasses import replace

import pytest
from test_agent_job_runner import HOME, config

from bus.messages import JobAssignment, VehicleCommand
from vehicle_agent.backends.base import VehicleSnapshot
from vehicle_agent.clock import TickClock
from vehicle_agent.job_runner import JobRunner
from vehicle_agent.rest import at_rest

LANDED = VehicleSnapshot(
    t_s=0.0,
    position_m_enu=HOME,
    velocity_mps_enu=(0.0, 0.0, 0.0),
    armed=False,
    mode="idle",
    on_ground=True,
)


def test_a_landed_vehicle_without_a_job_rests_and_one_with_a_job_does_not() -> None:
    runner = JobRunner(config())
    assert at_rest(runner, LANDED)
    assert not at_rest(runner, replace(LANDED, on_ground=False))
    assert not at_rest(runner, replace(LANDED, mode="takeoff"))
    job = JobAssignment(job_id="j1", text="L")
    assert runner.handle_command(VehicleCommand(command="assign", job=job), 0.0).ok
    assert not at_rest(runner, LANDED)  # preflight: the plan is on its way, take-off next


def test_an_operator_landed_or_stopped_vehicle_rests_too() -> None:
    runner = JobRunner(config())
    assert runner.handle_command(VehicleCommand(command="land"), 0.0).ok
    assert runner.state == "landed" and at_rest(runner, LANDED)
    assert runner.handle_command(VehicleCommand(command="estop"), 0.0).ok
    assert at_rest(runner, replace(LANDED, mode="estop"))


class FakeWall:
    def __init__(self) -> None:
        self.now_s = 100.0

    def __call__(self) -> float:
        return self.now_s


@pytest.mark.parametrize("skip_when_late", [False, True])
def test_the_clock_catches_up_with_the_wall_after_a_rest(skip_when_late: bool) -> None:
    wall = FakeWall()
    clock = TickClock(period_s=0.01, time_scale=4.0, skip_when_late=skip_when_late, wall_s=wall)
    clock.advance()
    wall.now_s += 1.0  # one wall second of rest: 4 agent seconds
    clock.catch_up()
    assert clock.now_s == pytest.approx(4.0, abs=0.01)
    assert clock.delay_s() == pytest.approx(0.0, abs=0.0025)  # the next tick is due now
    clock.catch_up()
    assert clock.now_s == pytest.approx(4.0, abs=0.01)  # idempotent
    wall.now_s -= 0.5
    clock.catch_up()
    assert clock.now_s == pytest.approx(4.0, abs=0.01)  # never back in time
