"""A ground vehicle's phases in the job runner (pure, an ideal vehicle): no climb, pen-up moves
sideways first then along x, and a reference that waits for a vehicle held back by a step."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from bus.messages import AgentReport, JobAssignment, VehicleCommand
from planner.samples import TrajectorySamples
from vehicle_agent.backends.base import Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.backends.kinematic import KinematicVehicle
from vehicle_agent.job_runner import JobRunner, PreparedJob, RunnerConfig

DT = 0.01
HOME: Vec3 = (0.0, 0.0, 0.0)
STEP_X_M = 1.0
"""The step's face: the vehicle stalls here for ``STALL_S``."""
STALL_S = 2.0


def ground_config(**overrides: object) -> RunnerConfig:
    values: dict[str, object] = {"route": "sideways_first", "transit_wait_m": 0.05}
    values.update(overrides)
    return RunnerConfig(
        vehicle_id="ground1",
        kind="omni-wheel",
        board_id="plaza",
        home_m_enu=HOME,
        cruise_z_m=0.0,
        v_max_mps=0.2,
        a_max_mps2=0.15,
        airborne=False,
        **values,  # type: ignore[arg-type]
    )


def floor_line() -> TrajectorySamples:
    """A pen-down line along x on the floor, from (2.0, 1.0) to (2.4, 1.0)."""
    t = np.linspace(0.0, 2.0, 201)
    x = 2.0 + 0.4 * t / 2.0
    p = np.column_stack([x, np.ones_like(x), np.zeros_like(x)])
    v = np.gradient(p, t, axis=0)
    return TrajectorySamples(t, p, v, np.zeros_like(p), (t > 0.2) & (t < 1.8))


class StallingVehicle(KinematicVehicle):
    """Follows its setpoints exactly, except that it stays at the step's face for a while."""

    def __init__(self) -> None:
        super().__init__(HOME, dt_s=DT)
        self.stall_ticks = round(STALL_S / DT)

    def tick(self, setpoint: Setpoint | None) -> VehicleSnapshot:
        here = self.position_m_enu
        at_face = here[0] < STEP_X_M <= (setpoint.position_m_enu[0] if setpoint else -1.0)
        if setpoint is not None and at_face and self.stall_ticks > 0:
            self.stall_ticks -= 1
            setpoint = Setpoint(position_m_enu=here)
        return super().tick(setpoint)


@dataclass
class GroundRun:
    runner: JobRunner
    vehicle: StallingVehicle = field(default_factory=StallingVehicle)
    reports: list[AgentReport] = field(default_factory=list)
    positions: list[Vec3] = field(default_factory=list)
    commands: list[str] = field(default_factory=list)
    written: int = 0

    def fly(self, max_s: float = 120.0) -> None:
        job = JobAssignment(job_id="j1", text="一", attempt=1)
        assert self.runner.handle_command(VehicleCommand(command="assign", job=job), 0.0).ok
        for k in range(round(max_s / DT)):
            actions = self.runner.step(self.vehicle.snapshot(), k * DT)
            if actions.backend_command is not None:
                name, hover = actions.backend_command
                self.commands.append(name)
                getattr(self.vehicle, name)(*(() if hover is None else (hover,)))
            if actions.plan_request is not None:
                self.runner.plan_ready(PreparedJob("j1", floor_line()))
            self.reports += actions.reports
            self.written += actions.finished is not None
            self.vehicle.tick(actions.setpoint)
            self.positions.append(self.vehicle.position_m_enu)
            if self.runner.phase == "ground" and len(self.commands) >= 2:
                return


def test_a_ground_vehicle_drives_sideways_then_along_x_and_waits_out_a_stall() -> None:
    run = GroundRun(JobRunner(ground_config()))
    run.fly()
    assert run.written == 1 and run.commands == ["takeoff", "land"]
    assert [r.event for r in run.reports if r.event != "progress"] == ["started"]
    path = np.asarray(run.positions)
    assert np.all(path[:, 2] == 0.0)  # never climbed
    out = path[: int(np.argmax(path[:, 0] >= 2.0))]  # to the start of the line
    assert np.all(out[out[:, 1] < 1.0 - 1e-9][:, 0] == 0.0)  # y first, at home's x
    back = path[int(np.argmax(path[:, 0] >= 2.4)) :]
    assert np.all(back[back[:, 1] > 1e-9][:, 0] >= 2.4 - 1e-9)  # back: y first, then x
    assert np.allclose(path[-1], HOME, atol=1e-6)


def test_without_waiting_the_stall_is_a_deviation_and_the_job_goes_back() -> None:
    run = GroundRun(JobRunner(ground_config(transit_wait_m=None)))
    run.fly()
    failed = [r for r in run.reports if r.event == "failed"]
    assert run.written == 0 and failed and failed[0].error is not None
    assert failed[0].error.code == "deviation" and failed[0].retry_after_s is not None


@given(
    start=st.tuples(*[st.floats(-5, 5)] * 3),
    end=st.tuples(*[st.floats(-5, 5)] * 3),
)
def test_sideways_first_legs_change_y_then_x_and_end_at_the_goal(start: Vec3, end: Vec3) -> None:
    legs = ground_config().legs(start, end)
    assert legs[-1] == end
    if len(legs) == 2:
        corner = legs[0]
        assert (corner[0], corner[2]) == (start[0], start[2]) and corner[1] == end[1]
    assert RunnerConfig("v", "k", None, HOME, 1.0, 1.0, 1.0).legs(start, end) == (end,)
