"""The pure decision logic of one vehicle agent, driven tick by tick against an ideal vehicle."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import pytest

from bus.messages import AgentReport, ErrorInfo, JobAssignment, Telemetry, VehicleCommand
from planner.samples import TrajectorySamples
from vehicle_agent.backends.base import Vec3
from vehicle_agent.backends.kinematic import KinematicVehicle
from vehicle_agent.job_runner import PREFLIGHT_HOLD_S, JobRunner, PreparedJob, RunnerConfig
from vehicle_agent.motion import PEAK_ACCEL_FACTOR, PEAK_SPEED_FACTOR, plan_move
from vehicle_agent.runner_io import AbortedJob
from vehicle_agent.trace import JobTrace

DT = 0.01
HOME: Vec3 = (0.0, -1.2, 0.0)
CRUISE_Z = 0.5
WRITE_Z = 0.35


def config(**overrides: float) -> RunnerConfig:
    values: dict[str, float] = {"v_max_mps": 0.6, "a_max_mps2": 0.8}
    values.update(overrides)
    return RunnerConfig(
        vehicle_id="uav1",
        kind="quadrotor-brush",
        board_id="b1",
        home_m_enu=HOME,
        cruise_z_m=CRUISE_Z,
        **values,
    )


def line_samples(duration_s: float = 2.0) -> TrajectorySamples:
    """Down to writing height, a pen-down line along x, back up: like a one-stroke plan."""
    n = round(duration_s / DT) + 1
    t = np.linspace(0.0, duration_s, n)
    u = t / duration_s

    def smooth(a: float, b: float) -> np.ndarray:
        w = np.clip((u - a) / (b - a), 0.0, 1.0)
        return w * w * (3.0 - 2.0 * w)

    x = smooth(0.25, 0.75) * 0.4 - 0.2
    z = CRUISE_Z - (CRUISE_Z - WRITE_Z) * (smooth(0.0, 0.2) - smooth(0.8, 1.0))
    p = np.column_stack([x, np.zeros(n), z])
    v = np.gradient(p, t, axis=0)
    return TrajectorySamples(t, p, v, np.zeros((n, 3)), z <= WRITE_Z + 1e-9)


@dataclass
class Run:
    """A runner, an ideal vehicle and everything the runner said, advanced tick by tick."""

    runner: JobRunner = field(default_factory=lambda: JobRunner(config()))
    vehicle: KinematicVehicle = field(default_factory=lambda: KinematicVehicle(HOME, dt_s=DT))
    ticks: int = 0
    reports: list[AgentReport] = field(default_factory=list)
    telemetry: list[Telemetry] = field(default_factory=list)
    telemetry_phases: list[str] = field(default_factory=list)
    """The runner's phase when each telemetry message was made."""
    finished: list[JobTrace] = field(default_factory=list)
    aborted: list[AbortedJob] = field(default_factory=list)
    states: list[str] = field(default_factory=list)
    positions: list[Vec3] = field(default_factory=list)
    samples: TrajectorySamples = field(default_factory=line_samples)
    auto_plan: bool = True
    commands: list[str] = field(default_factory=list)
    refuse_takeoffs: int = 0
    """The vehicle refuses this many take-offs (pre-arm checks) before it flies."""
    preflight: str | None = None
    """What the vehicle says of its pre-arm checks (None: they pass)."""
    not_ready_takeoffs: int = 0
    """This many take-offs meet checks that have just begun failing (nothing asked of it)."""

    def tick(self) -> None:
        snapshot = replace(self.vehicle.snapshot(), preflight=self.preflight)
        actions = self.runner.step(snapshot, self.now_s)
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            self.commands.append(name)
            if name == "takeoff" and self.not_ready_takeoffs > 0:
                self.not_ready_takeoffs -= 1
                self.runner.takeoff_refused("not arming: checks fail", self.now_s, not_ready=True)
            elif name == "takeoff" and self.refuse_takeoffs > 0:
                self.refuse_takeoffs -= 1
                self.runner.takeoff_refused("PreArm: Compass not calibrated", self.now_s)
            else:
                getattr(self.vehicle, name)(*(() if hover is None else (hover,)))
        if actions.plan_request is not None and self.auto_plan:
            self.runner.plan_ready(PreparedJob(actions.plan_request.job_id, self.samples))
        self.vehicle.tick(actions.setpoint)
        self.reports.extend(actions.reports)
        if actions.telemetry is not None:
            self.telemetry.append(actions.telemetry)
            self.telemetry_phases.append(self.runner.phase)
        if actions.finished is not None:
            self.finished.append(actions.finished)
        if actions.aborted is not None:
            self.aborted.append(actions.aborted)
        if not self.states or self.states[-1] != self.runner.state:
            self.states.append(self.runner.state)
        self.positions.append(self.vehicle.position_m_enu)
        self.ticks += 1

    @property
    def now_s(self) -> float:
        return self.ticks * DT

    def until(self, done: Callable[[], bool], max_s: float = 60.0) -> None:
        end = self.now_s + max_s
        while not done():
            assert self.now_s < end, f"timed out in state {self.runner.state}/{self.runner.phase}"
            self.tick()

    def command(self, name: str, **kwargs: object) -> bool:
        reply = self.runner.handle_command(VehicleCommand(command=name, **kwargs), self.now_s)  # type: ignore[arg-type]
        return reply.ok

    def assign(self, job_id: str = "j1") -> bool:
        self.runner.set_orchestrator_alive(True, self.now_s)
        return self.command("assign", job=JobAssignment(job_id=job_id, text="L"))

    def events(self) -> list[str]:
        return [r.event for r in self.reports if r.event != "progress"]


def test_a_job_goes_through_every_state_and_flies_the_plan_exactly() -> None:
    run = Run()
    assert run.assign()
    run.until(lambda: run.runner.state == "idle" and run.runner.phase == "ground")
    assert run.states == ["taking_off", "writing", "returning", "landing", "idle"]
    assert run.events() == ["started"]
    assert run.reports[0].planned_duration_s == pytest.approx(2.0)
    progress = [r.progress for r in run.reports if r.event == "progress"]
    assert progress == sorted(progress) and 0.4 < progress[0] < 0.6  # 1 s of 2 s
    (trace,) = run.finished
    flown = trace.flown  # no pen known: the writing point is the vehicle's position
    assert not trace.pen_known and flown.base_m_enu is None
    assert flown.t_s.shape[0] == pytest.approx(201, abs=1)
    np.testing.assert_allclose(
        flown.writing_point_m_enu[1:], flown.reference_m_enu[:-1], atol=1e-12
    )
    assert flown.pen_down.sum() == (run.samples.pen_down).sum()
    assert run.vehicle.position_m_enu == pytest.approx(HOME, abs=1e-6)
    assert run.commands == ["takeoff", "land"]


def test_transit_moves_respect_the_speed_limit() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.runner.state == "idle" and run.runner.phase == "ground")
    p = np.asarray(run.positions)
    speed = np.linalg.norm(np.diff(p, axis=0), axis=1) / DT
    assert speed.max() <= 0.6 * 1.001  # transit moves and the plan itself
    assert np.all(p[:, 2] >= HOME[2] - 1e-12)


def test_orchestrator_loss_while_writing_interrupts_nothing() -> None:
    """Only the orchestrator assigns, and it keeps the job for its writer (the lease, applied by
    the service, bounds how long the vehicle may write unheard): the character is finished."""
    run = Run()
    run.assign()
    run.until(lambda: run.runner.state == "writing" and run.vehicle.position_m_enu[2] < 0.4)
    run.runner.set_orchestrator_alive(False, run.now_s)
    assert run.runner.status().job_id == "j1" and run.runner.phase == "write"
    run.until(lambda: run.runner.phase == "ground")
    assert run.runner.state == "idle" and [f.job_id for f in run.finished] == ["j1"]
    assert run.events() == ["started"]  # the result is the service's report


def test_a_settled_vehicle_holds_the_start_until_the_lease_lets_it_write() -> None:
    run = Run()
    run.assign()
    run.runner.may_begin_writing = False  # the orchestrator went away before writing began
    run.until(lambda: run.runner.phase == "settle")
    for _ in range(1000):  # 10 s: far past the settle timeout, never a not_settled abort
        run.tick()
    assert (run.runner.phase, run.runner.state) == ("settle", "taking_off")
    assert run.events() == [] and run.runner.status().job_id == "j1"
    run.runner.may_begin_writing = True  # confirmed again
    run.until(lambda: run.runner.phase == "ground")
    assert [f.job_id for f in run.finished] == ["j1"]


def test_loss_while_idle_changes_nothing() -> None:
    run = Run()
    run.runner.set_orchestrator_alive(True, 0.0)
    run.runner.set_orchestrator_alive(False, 0.0)
    for _ in range(500):
        run.tick()
    assert run.vehicle.mode == "idle" and run.states == ["idle"]


def test_cancel_lifts_returns_and_lands_without_a_report() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.runner.state == "writing" and run.vehicle.position_m_enu[2] < 0.4)
    assert run.command("cancel", job_id="j1")
    run.until(lambda: run.runner.phase == "ground")
    assert run.runner.state == "idle" and not run.finished
    assert run.events() == ["started"]
    lift = [p for p in run.positions[-400:] if p[2] > 0.0]
    assert max(p[2] for p in lift) == pytest.approx(CRUISE_Z)
    assert_kept_unreported(run, "cancelled")


def assert_kept_unreported(run: Run, reason: str) -> None:
    """What was flown of the job broken off is kept (to measure and archive), with no report."""
    (aborted,) = run.aborted
    flown = aborted.trace.flown
    assert aborted.report is None and flown.abort_reason == reason
    assert 0.0 <= flown.t_s[-1] < run.samples.duration_s and aborted.trace.job_id == "j1"
    assert len(flown.t_s) == round(flown.t_s[-1] / DT) + 1  # every tick since writing began


def test_cancel_of_another_job_is_ignored() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.runner.state == "writing")
    assert run.command("cancel", job_id="other")
    run.until(lambda: run.runner.phase == "ground")
    assert len(run.finished) == 1 and not run.aborted


def test_estop_cuts_motors_abandons_the_job_and_refuses_new_ones() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.runner.state == "writing")
    assert run.command("estop")
    run.tick()
    assert run.vehicle.mode == "estop" and run.runner.state == "fault"
    assert run.events() == ["started"] and run.runner.status().job_id is None
    assert not run.assign("j2")
    assert_kept_unreported(run, "estop")


def test_pre_arm_checks_failing_are_in_the_status_with_one_event_as_they_fail_and_pass() -> None:
    runner = JobRunner(config())
    ready = KinematicVehicle(HOME, dt_s=DT).snapshot()
    why = "Preflight Fail: horizontal velocity unstable"
    waiting = replace(ready, preflight=why)
    events: list[tuple[str, str]] = []
    for k in range(3400):  # 34 s of ticks waiting, then ready
        actions = runner.step(waiting if k < 3400 - 1 else ready, 10.0 + k * DT)
        events += [(e.level, e.message) for e in actions.events if e.kind == "preflight"]
        if k == 100:
            assert runner.status().preflight == why
    assert events == [
        ("warning", f"uav1 held by its preflight: {why}"),
        ("info", "uav1 preflight passes after 34 s"),
    ]
    assert runner.status().preflight == ""


def test_a_planned_job_takes_off_the_moment_the_pre_arm_checks_pass() -> None:
    """No take-off is asked while the autopilot says its checks fail (PX4 flips them every few
    seconds on the ground); the first tick they pass, it goes; nothing is handed back."""
    run = Run(preflight="Preflight Fail: horizontal velocity unstable")
    assert run.assign()
    run.until(lambda: run.now_s > 12.0)
    assert (run.runner.phase, run.commands, run.reports) == ("preflight", [], [])
    run.preflight = None
    run.tick()
    assert run.commands == ["takeoff"]
    run.until(lambda: run.runner.state == "idle" and run.runner.phase == "ground")
    assert run.events() == ["started"]


def test_checks_that_never_pass_hand_the_job_back_after_the_hold() -> None:
    run = Run(preflight="Preflight Fail: vertical velocity unstable")
    assert run.assign()
    run.until(lambda: bool(run.reports), max_s=PREFLIGHT_HOLD_S + 1.0)
    assert PREFLIGHT_HOLD_S < run.now_s < PREFLIGHT_HOLD_S + 0.1 and run.commands == []
    (report,) = run.reports
    assert report.error is not None and report.error.code == "takeoff_refused"
    assert "vertical velocity unstable" in report.error.message


def test_checks_that_fail_as_it_takes_off_are_waited_for_again() -> None:
    """The autopilot was not asked (the backend's NotReadyError): back to waiting, job kept."""
    run = Run(not_ready_takeoffs=2)
    assert run.assign()
    run.until(lambda: run.runner.state == "idle" and run.runner.phase == "ground")
    assert run.commands == ["takeoff", "takeoff", "takeoff", "land"]
    assert run.events() == ["started"]


def test_a_refused_takeoff_hands_the_job_back_and_backs_off_twice_as_long_each_time() -> None:
    run = Run(refuse_takeoffs=2)
    assert run.assign("j1")
    for _ in range(3):  # plan on the ground, take off (refused), report
        run.tick()
    (report,) = run.reports
    assert (report.event, report.job_id, report.retry_after_s) == ("failed", "j1", 5.0)
    assert report.error is not None and report.error.code == "takeoff_refused"
    status = run.runner.status()
    assert (status.state, status.job_id) == ("idle", None) and "Compass" in status.message
    assert run.vehicle.mode == "idle"
    refused_at = run.now_s
    run.until(lambda: run.now_s >= refused_at + 4.9)
    reply = run.runner.handle_command(
        VehicleCommand(command="assign", job=JobAssignment(job_id="j2", text="L")), run.now_s
    )
    assert not reply.ok and reply.error is not None and reply.error.code == "takeoff_refused"
    run.until(lambda: run.now_s >= refused_at + 5.1)
    assert run.assign("j2")
    run.until(lambda: len(run.reports) == 2)
    assert run.reports[1].retry_after_s == 10.0  # refused again: twice as long
    refused_at = run.now_s
    run.until(lambda: run.now_s >= refused_at + 10.1)
    assert run.assign("j3")  # this time it flies
    run.until(lambda: len(run.finished) == 1 and run.runner.phase == "ground")
    assert run.finished[0].job_id == "j3"
    run.refuse_takeoffs = 1
    assert run.assign("j4")
    run.until(lambda: run.events().count("failed") == 3)
    assert run.reports[-1].retry_after_s == 5.0  # it flew in between: back to the first backoff


def test_assign_while_busy_is_refused_but_a_repeat_is_accepted() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.runner.state == "writing")
    reply = run.runner.handle_command(
        VehicleCommand(command="assign", job=JobAssignment(job_id="j2", text="A")), run.now_s
    )
    assert not reply.ok and reply.error is not None and reply.error.code == "busy"
    assert run.assign("j1")


def test_plan_failure_reports_and_never_takes_off() -> None:
    run = Run(auto_plan=False)
    run.assign()
    for _ in range(50):  # planning takes a while: the vehicle waits on the ground
        run.tick()
    assert (run.runner.phase, run.vehicle.mode, run.commands) == ("preflight", "idle", [])
    run.runner.plan_failed("j1", ErrorInfo(code="invalid_strokes", message="bad", stroke_index=2))
    run.tick()
    assert (run.runner.phase, run.runner.state, run.commands) == ("ground", "idle", [])
    (report,) = run.reports
    assert report.event == "failed" and report.error is not None
    assert report.error.stroke_index == 2


def test_land_command_while_writing_ends_landed() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.runner.state == "writing")
    assert run.command("land")
    run.until(lambda: run.runner.phase == "ground")
    assert run.runner.state == "landed" and run.events() == ["started"]
    assert run.assign("j2")
    assert_kept_unreported(run, "landed_by_operator")


def test_telemetry_comes_at_its_period() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.now_s > 2.0 - DT / 2)  # ticks at 0, 0.01, ..., 1.99
    assert len(run.telemetry) == 40
    t = [m.t_s for m in run.telemetry]
    assert np.diff(t) == pytest.approx(np.full(39, 0.05))
    assert {m.job_id for m in run.telemetry} == {"j1"}


class ShortClimber(KinematicVehicle):
    """A vehicle whose take-off ends 8 cm short of the hover height (PX4 on its own climb ramp
    trails it, and the take-off counts as complete within ``takeoff_tolerance_m``)."""

    def takeoff(self, hover_m_enu: Vec3) -> None:
        super().takeoff((hover_m_enu[0], hover_m_enu[1], hover_m_enu[2] - 0.08))


def test_the_transit_starts_where_the_climb_left_the_vehicle() -> None:
    """Not at the hover point it was climbing to: a reference 8 cm away at the first tracked
    tick was an orchestrator alert (0.05 m) at every PX4 take-off."""
    run = Run(vehicle=ShortClimber(HOME, dt_s=DT))
    run.assign()
    run.until(lambda: "land" in run.commands and run.runner.phase == "ground")
    told = list(zip(run.telemetry_phases, run.telemetry, strict=True))
    transit = [m.tracking_error_m for phase, m in told if phase == "transit"]
    assert transit and max(transit) < 0.01


def test_status_follows_the_state() -> None:
    run = Run()
    assert run.runner.status().state == "idle"
    run.assign()
    status = run.runner.status()
    assert (status.state, status.job_id, status.board_id) == ("taking_off", "j1", "b1")


@pytest.mark.parametrize("distance", [0.05, 0.5, 3.0])
def test_quintic_move_peaks_match_the_closed_form(distance: float) -> None:
    move = plan_move((0.0, 0.0, 1.0), (distance, 0.0, 1.0), 2.0, v_max_mps=0.6, a_max_mps2=0.8)
    t = np.linspace(move.t0_s, move.end_s, 20001)
    sp = [move.setpoint(float(x)) for x in t]
    v = np.array([s.velocity_mps_enu[0] for s in sp])
    a = np.array([s.acceleration_mps2_enu[0] for s in sp])
    x = np.array([s.position_m_enu[0] for s in sp])
    big_t = move.duration_s
    assert v.max() == pytest.approx(PEAK_SPEED_FACTOR * distance / big_t, rel=1e-6)
    assert a.max() == pytest.approx(PEAK_ACCEL_FACTOR * distance / big_t**2, rel=1e-6)
    assert v.max() <= 0.6 + 1e-9 and a.max() <= 0.8 + 1e-9
    assert math.isclose(v.max(), 0.6, rel_tol=1e-6) or math.isclose(a.max(), 0.8, rel_tol=1e-6)
    np.testing.assert_allclose(np.gradient(x, t), v, atol=1e-4)
    assert (x[0], x[-1]) == (0.0, pytest.approx(distance))
