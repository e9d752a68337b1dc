"""The agent's hold on its job (``vehicle_agent/lease.py``) and leaving ``fault`` (``fault.py``)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from bus.messages import JobAssignment, VehicleCommand
from planner.samples import TrajectorySamples
from vehicle_agent.backends.base import VehicleSnapshot
from vehicle_agent.backends.kinematic import KinematicVehicle
from vehicle_agent.fault import clear_fault, unsafe_because
from vehicle_agent.job_runner import JobRunner, PreparedJob, RunnerConfig
from vehicle_agent.lease import JobLease

LOST_AFTER_S = 1.5


def test_a_stall_of_lost_after_s_voids_the_lease_in_any_phase_a_shorter_one_does_not() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=False, now_s=0.0)
    lease.tick_done(0.0)
    assert lease.breach(lease.tick(1.4), 1.4) is None  # 1.4 s: the orchestrator may still see it
    lease.tick_done(1.4)
    why = lease.breach(lease.tick(1.4 + LOST_AFTER_S), 1.4 + LOST_AFTER_S)
    assert why == "this agent stalled for 1.5 s"
    assert JobLease(LOST_AFTER_S).breach(10.0, 10.0) is None  # no job: nothing to give up


def test_writing_needs_a_confirmation_younger_than_the_lease_not_only_a_recent_start() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=False, now_s=0.0)  # assigned at 0; transit takes 5 s
    assert lease.breach(0.0, 4.0) is None  # unconfirmed in transit: no ink, nothing to give up
    lease.hold("j1", active=True, writing=True, now_s=5.0)
    # the brush would touch 5 s after the last word from the orchestrator: it may have given
    # the job away meanwhile (the old rule counted from the start of writing and wrote on)
    assert lease.breach(0.0, 5.0) == "no acknowledgement from the orchestrator for 5.0 s"


def test_a_flown_job_asks_for_confirmations_before_and_while_writing() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=False, now_s=0.0)
    assert not lease.wants_probe(0.4) and lease.wants_probe(0.5)  # in transit too
    lease.acknowledged("j1", sent_at_s=4.9)
    lease.hold("j1", active=True, writing=True, now_s=5.0)
    assert lease.breach(0.0, 5.0) is None and not lease.wants_probe(5.3)
    assert lease.wants_probe(5.4)
    lease.acknowledged("j1", sent_at_s=5.5)
    lease.acknowledged("j0", sent_at_s=6.9)  # another job's receipt proves nothing
    assert lease.breach(0.0, 6.9) is None
    assert lease.breach(0.0, 7.0) == "no acknowledgement from the orchestrator for 1.5 s"
    lease.hold(None, active=False, writing=False, now_s=7.0)
    assert lease.job_id is None and lease.breach(0.0, 99.0) is None


def test_a_job_no_longer_flown_asks_nothing() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=False, writing=False, now_s=0.0)  # returning, its result on its way
    assert not lease.wants_probe(10.0)


def test_unconfirmed_writing_asks_for_a_confirmation_at_most_once_a_third_of_the_lease() -> None:
    lease = JobLease(LOST_AFTER_S)  # probes every 0.5 s
    lease.hold("j1", active=True, writing=True, now_s=0.0)
    assert not lease.probe_due(0.4)
    asked = [t for t in (0.5, 0.6, 0.9, 1.0, 1.2) if lease.probe_due(t)]
    assert asked == [0.5, 1.0]
    lease.acknowledged("j1", sent_at_s=1.2)
    assert not lease.probe_due(1.6)  # confirmed at 1.2: nothing to ask before 1.7


def test_a_later_job_starts_with_a_fresh_lease() -> None:
    lease = JobLease(LOST_AFTER_S)
    lease.hold("j1", active=True, writing=True, now_s=0.0)
    lease.hold("j2", active=True, writing=True, now_s=10.0)
    assert lease.breach(0.0, 11.0) is None and lease.confirmed_at_s == 10.0


# --- clear_fault ---------------------------------------------------------------------------------

HOME = (0.0, -1.2, 0.0)


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
    return JobRunner(config)


def _hover_then_estop(runner: JobRunner, vehicle: KinematicVehicle) -> float:
    """Take a job, fly until airborne, emergency stop; returns the time."""
    runner.set_orchestrator_alive(True, 0.0)
    assign = VehicleCommand(command="assign", job=JobAssignment(job_id="j1", text="L"))
    assert runner.handle_command(assign, 0.0).ok
    now, dt = 0.0, vehicle.dt_s
    for _ in range(3000):
        actions = runner.step(vehicle.snapshot(), now)
        if actions.plan_request is not None:
            runner.plan_ready(_hold_plan(runner))
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            getattr(vehicle, name)(*(() if hover is None else (hover,)))
        vehicle.tick(actions.setpoint)
        now += dt
        if not vehicle.snapshot().on_ground and runner.phase != "climb":
            break
    assert not vehicle.snapshot().on_ground
    assert runner.handle_command(VehicleCommand(command="estop"), now).ok
    actions = runner.step(vehicle.snapshot(), now)
    assert actions.backend_command == ("estop", None)
    vehicle.estop()
    return now


def _hold_plan(runner: JobRunner) -> PreparedJob:
    """A plan that only hovers (the vehicle is stopped before it writes)."""
    hover = np.array([runner.config.hover_home_m_enu] * 2)
    t = np.array([0.0, 1.0])
    samples = TrajectorySamples(t, hover, np.zeros((2, 3)), np.zeros((2, 3)), np.zeros(2, bool))
    return PreparedJob("j1", samples)


def test_an_estopped_vehicle_leaves_fault_only_at_rest_and_disarmed() -> None:
    runner, vehicle = _runner(), KinematicVehicle(HOME, dt_s=0.01)
    _hover_then_estop(runner, vehicle)
    assert (runner.state, runner.phase) == ("fault", "stopped")
    at_rest = vehicle.snapshot()
    assert at_rest.on_ground and not at_rest.armed
    flying = replace(at_rest, on_ground=False, armed=True)
    refused = clear_fault(runner, flying)
    assert not refused.ok and refused.error is not None and refused.error.code == "unsafe"
    assert "not on the ground" in refused.message and runner.state == "fault"
    faulty = replace(at_rest, fault="lost link")
    assert unsafe_because(faulty) == "the vehicle still reports a fault: lost link"
    assert unsafe_because(replace(at_rest, armed=True)) == "its motors are armed"
    cleared = clear_fault(runner, at_rest)
    assert cleared.ok and (runner.state, runner.phase) == ("landed", "ground")
    assert clear_fault(runner, at_rest).message == "uav1 is not in fault (landed)"
    assign = VehicleCommand(command="assign", job=JobAssignment(job_id="j2", text="I"))
    assert runner.handle_command(assign, 100.0).ok  # it can fly again


@pytest.mark.parametrize("state", ["idle", "writing"])
def test_clear_fault_does_nothing_to_a_vehicle_not_in_fault(state: str) -> None:
    runner = _runner()
    runner.state = state  # type: ignore[assignment]
    snap = VehicleSnapshot(
        t_s=0.0,
        position_m_enu=HOME,
        velocity_mps_enu=(0.0, 0.0, 0.0),
        armed=False,
        mode="idle",
        on_ground=True,
    )
    reply = clear_fault(runner, snap)
    assert reply.ok and runner.state == state
