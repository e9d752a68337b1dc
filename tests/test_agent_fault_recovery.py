"""Every stop can be undone: an e-stopped vehicle flies its next job after ``clear_fault``.

On each backend the agent has (the kinematic and the simulated vehicle in-process; MAVLink to
the MAVLink vehicle simulator in both autopilots' flavours, real bytes over UDP): a vehicle
stopped in the air rests on the ground, the operator's ``clear_fault`` is refused while it is
not safe and then brings the runner to ``landed`` and the backend to ``idle``, and the next
take-off really climbs (before, the backend stayed in ``estop`` and refused it).
"""

from __future__ import annotations

import asyncio
from dataclasses import replace

import numpy as np
import pytest

from bus.messages import JobAssignment, VehicleCommand
from mavsim.config import VehicleConfig
from mavsim.server import MavsimServer
from planner.samples import TrajectorySamples
from vehicle_agent.backends.base import (
    BackendError,
    SynchronousBackend,
    VehicleBackend,
    VehicleSnapshot,
)
from vehicle_agent.backends.kinematic import KinematicVehicle
from vehicle_agent.backends.mavlink.backend import MavlinkBackend
from vehicle_agent.backends.mavlink.settings import MavlinkSettings
from vehicle_agent.backends.sim import SimBackend, SimVehicle
from vehicle_agent.fault import clear_fault, unsafe_because
from vehicle_agent.job_runner import JobRunner, PreparedJob, RunnerConfig

pytestmark = pytest.mark.timeout(90)

HOME = (0.0, -1.2, 0.0)
MAVSIM_SCALE = 2.0


def _runner() -> JobRunner:
    config = RunnerConfig(
        vehicle_id="uav1",
        kind="quadrotor-brush",
        board_id="b1",
        home_m_enu=HOME,
        cruise_z_m=0.5,
        v_max_mps=0.6,
        a_max_mps2=0.8,
    )
    runner = JobRunner(config)
    runner.set_orchestrator_alive(True, 0.0)
    return runner


AWAY_M = 0.5
"""How far east of home in [m] the first job's plan hovers (where the vehicle is stopped)."""


def _hover_plan(runner: JobRunner, job_id: str) -> PreparedJob:
    """A plan that only hovers (the vehicle is stopped before it writes): the first job away
    from home, the next above home."""
    x_m, y_m, z_m = runner.config.hover_home_m_enu
    away = AWAY_M if job_id == "j1" else 0.0
    hover = np.array([(x_m + away, y_m, z_m)] * 2)
    t = np.array([0.0, 1.0])
    samples = TrajectorySamples(t, hover, np.zeros((2, 3)), np.zeros((2, 3)), np.zeros(2, bool))
    return PreparedJob(job_id, samples)


class Agent:
    """The agent's loop reduced to the runner and one backend, paced for MAVLink."""

    def __init__(self, runner: JobRunner, backend: VehicleBackend, scale: float | None) -> None:
        self.runner, self.backend, self.scale = runner, backend, scale
        self.now_s = 1000.0
        self.snapshot: VehicleSnapshot | None = None

    async def tick(self) -> None:
        """One control period, as the agent's loop runs it."""
        if self.snapshot is None:
            self.snapshot = await self.backend.tick(None, self.now_s)
        actions = self.runner.step(self.snapshot, self.now_s)
        if actions.plan_request is not None:
            self.runner.plan_ready(_hover_plan(self.runner, actions.plan_request.job_id))
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            if name == "takeoff" and hover is not None:
                await self.backend.takeoff(hover)
            elif name == "estop":
                await self.backend.estop()
        self.snapshot = await self.backend.tick(actions.setpoint, self.now_s)
        self.now_s += self.backend.control_period_s
        if self.scale is not None:
            await asyncio.sleep(self.backend.control_period_s / self.scale)

    async def until_settling(self, job_id: str, within_s: float) -> None:
        """Give the runner ``job_id`` and fly until it holds the start of the plan."""
        assign = VehicleCommand(command="assign", job=JobAssignment(job_id=job_id, text="L"))
        assert self.runner.handle_command(assign, self.now_s).ok
        end = self.now_s + within_s
        while self.now_s < end:
            await self.tick()
            if self.runner.phase == "settle":
                return
            assert self.runner.state != "fault", self.runner.message
        raise AssertionError(
            f"{job_id}: not at its start within {within_s} s ({self.runner.message})"
        )

    async def until_at_rest(self, within_s: float) -> None:
        end = self.now_s + within_s
        while self.now_s < end:
            await self.tick()
            assert self.snapshot is not None
            if self.snapshot.on_ground and not self.snapshot.armed:
                return
        raise AssertionError(f"not at rest within {within_s} s")


async def _estop_then_fly_again(agent: Agent) -> None:
    runner = agent.runner
    await agent.until_settling("j1", within_s=30.0)  # hovering away from home
    assert runner.handle_command(VehicleCommand(command="estop"), agent.now_s).ok
    await agent.tick()
    assert (runner.state, runner.phase) == ("fault", "stopped")
    await agent.until_at_rest(within_s=10.0)
    at_rest = agent.snapshot
    assert at_rest is not None
    refused = await clear_fault(runner, replace(at_rest, armed=True), agent.backend)
    assert not refused.ok and "its motors are armed" in refused.message
    assert runner.state == "fault"
    cleared = await clear_fault(runner, at_rest, agent.backend)
    assert cleared.ok, cleared.message
    assert (runner.state, runner.phase) == ("landed", "ground")
    await agent.tick()
    assert agent.snapshot is not None and agent.snapshot.mode == "idle"
    runner.state = "idle"  # released by the operator (the orchestrator's hold)
    # the next job takes off for real, where it fell, and flies from there to its start
    await agent.until_settling("j2", within_s=30.0)
    assert agent.snapshot is not None
    assert abs(agent.snapshot.position_m_enu[0] - HOME[0]) < 0.05, agent.snapshot.position_m_enu


@pytest.mark.parametrize("vehicle", ["kinematic", "sim"])
def test_an_estopped_in_process_vehicle_flies_again_after_clear_fault(vehicle: str) -> None:
    if vehicle == "kinematic":
        backend: VehicleBackend = SynchronousBackend(KinematicVehicle(HOME, dt_s=0.01))
    else:
        backend = SimBackend(SimVehicle(HOME))
    asyncio.run(_estop_then_fly_again(Agent(_runner(), backend, scale=None)))


@pytest.mark.parametrize("autopilot", ["ardupilot", "px4"])
def test_an_estopped_autopilot_rearms_through_its_checks_after_clear_fault(autopilot: str) -> None:
    config = VehicleConfig(vehicle_id="uav1", system_id=7, port=0, home_m_enu=HOME,
                           autopilot=autopilot, position_source_delay_s=0.0)  # fmt: skip
    server = MavsimServer([config], time_scale=MAVSIM_SCALE).start()

    async def scenario() -> None:
        url = server.endpoints[0].url
        backend = MavlinkBackend(MavlinkSettings(url=url, origin_m_enu=HOME))
        await backend.start()
        try:
            await _estop_then_fly_again(Agent(_runner(), backend, scale=MAVSIM_SCALE))
            assert server.endpoints[0].autopilot.armed  # armed again by the normal take-off
        finally:
            await backend.close()

    try:
        asyncio.run(scenario())
    finally:
        server.stop()


def test_a_vehicle_not_at_rest_stays_in_fault_and_the_backend_refuses_to_recover() -> None:
    vehicle = KinematicVehicle(HOME, dt_s=0.01)
    vehicle.takeoff((HOME[0], HOME[1], 0.5))
    with pytest.raises(BackendError, match="not at rest"):
        vehicle.recover()
    flying = vehicle.tick(None)
    assert unsafe_because(flying) == "it is not on the ground"
    assert unsafe_because(replace(flying, on_ground=True)) == "its motors are armed"


def test_a_lost_autopilot_link_keeps_the_fault() -> None:
    backend = MavlinkBackend(MavlinkSettings(url="udpin:127.0.0.1:1", origin_m_enu=HOME))
    with pytest.raises(BackendError, match="no link"):
        asyncio.run(backend.recover())
