"""Safety aborts of the job runner against an ideal vehicle that can be pushed off its track.

Deviation (while writing: final failure; before: the job goes back to the queue), the abort
policies, settling (re-fly the approach, then ``not_settled``), the geofence (plans refused before
take-off, a vehicle outside it holds and lands where it is, then ``fault``), events for the
autopilot's mode and faults, and the writing-bounds verdict of a written job.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import pytest
from job_traces import recorded_trace

from bus.messages import AgentReport, JobAssignment, JobMetrics, VehicleCommand
from planner.samples import TrajectorySamples
from vehicle_agent.backends.base import Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.backends.kinematic import KinematicVehicle
from vehicle_agent.job_runner import JobRunner, PreparedJob, RunnerConfig
from vehicle_agent.runner_io import AbortedJob, RunnerEvent, result_report
from vehicle_agent.runner_phases import unsettled_reason
from vehicle_agent.safety import DeviationLimit, SafetyLimits, WritingBounds, vehicle_fence
from vehicle_agent.trace import JobTrace

DT = 0.01
HOME: Vec3 = (0.0, -1.2, 0.0)
CRUISE_Z, WRITE_Z = 0.5, 0.35
BOARD = [(-0.7, -0.7), (0.7, -0.7), (0.7, 0.7), (-0.7, 0.7)]
FENCE = vehicle_fence(BOARD, HOME, CRUISE_Z, margin_m=0.5, ceiling_margin_m=0.5)


def limits(**overrides: object) -> SafetyLimits:
    base = SafetyLimits(deviation=DeviationLimit(0.15, 0.3), fence=FENCE, abort_backoff_s=20.0)
    return replace(base, **overrides)  # type: ignore[arg-type]


def line_samples(duration_s: float = 4.0, y_m: float = 0.0) -> TrajectorySamples:
    """Down to writing height, a pen-down line along x, back up."""
    n = round(duration_s / DT) + 1
    t = np.linspace(0.0, duration_s, n)
    u = t / duration_s

    def smooth(a: float, b: float) -> np.ndarray:
        w = np.clip((u - a) / (b - a), 0.0, 1.0)
        return w * w * (3.0 - 2.0 * w)

    x = smooth(0.25, 0.75) * 0.4 - 0.2
    z = CRUISE_Z - (CRUISE_Z - WRITE_Z) * (smooth(0.0, 0.2) - smooth(0.8, 1.0))
    p = np.column_stack([x, np.full(n, y_m), z])
    return TrajectorySamples(t, p, np.gradient(p, t, axis=0), np.zeros((n, 3)), z <= WRITE_Z + 1e-9)


class PushedVehicle(KinematicVehicle):
    """Follows setpoints exactly, plus an offset that ``push(t)`` says (a gust, a bad sensor)."""

    def __init__(self, push: Callable[[float], Vec3]) -> None:
        super().__init__(HOME, dt_s=DT)
        self.push = push
        self.pen_z_m = WRITE_Z + 1e-6

    def tick(self, setpoint: Setpoint | None) -> VehicleSnapshot:
        snapshot = super().tick(setpoint)
        if setpoint is None or self.mode != "offboard":
            return snapshot
        dx, dy, dz = self.push(self.t_s)
        x, y, z = setpoint.position_m_enu
        self.position_m_enu = (x + dx, y + dy, z + dz)
        return self.snapshot()


@dataclass
class Run:
    safety: SafetyLimits = field(default_factory=limits)
    push: Callable[[float], Vec3] = lambda _t: (0.0, 0.0, 0.0)
    samples: TrajectorySamples = field(default_factory=line_samples)
    runner: JobRunner = field(init=False)
    vehicle: PushedVehicle = field(init=False)
    ticks: int = 0
    reports: list[AgentReport] = field(default_factory=list)
    events: list[RunnerEvent] = field(default_factory=list)
    commands: list[str] = field(default_factory=list)
    phases: list[str] = field(default_factory=list)
    contact: list[tuple[float, bool]] = field(default_factory=list)
    finished: list[JobTrace] = field(default_factory=list)
    aborted: list[AbortedJob] = field(default_factory=list)

    def __post_init__(self) -> None:
        config = RunnerConfig(vehicle_id="uav1", kind="quadrotor-brush", board_id="b1",
                              home_m_enu=HOME, cruise_z_m=CRUISE_Z, v_max_mps=0.6, a_max_mps2=0.8,
                              safety=self.safety)  # fmt: skip
        self.runner = JobRunner(config)
        self.vehicle = PushedVehicle(self.push)

    @property
    def now_s(self) -> float:
        return self.ticks * DT

    def tick(self, snapshot: VehicleSnapshot | None = None) -> None:
        actions = self.runner.step(snapshot or self.vehicle.snapshot(), self.now_s)
        if actions.backend_command is not None:
            name, hover = actions.backend_command
            self.commands.append(name)
            getattr(self.vehicle, name)(*(() if hover is None else (hover,)))
        if actions.plan_request is not None:
            self.runner.plan_ready(PreparedJob(actions.plan_request.job_id, self.samples))
        self.vehicle.tick(actions.setpoint)
        self.reports.extend(r for r in actions.reports if r.event != "progress")
        self.events.extend(actions.events)
        if actions.finished is not None:
            self.finished.append(actions.finished)
        if actions.aborted is not None:  # its report goes once measured (the service's part)
            self.aborted.append(actions.aborted)
            self.reports.extend(r for r in [actions.aborted.report] if r is not None)
        if not self.phases or self.phases[-1] != self.runner.phase:
            self.phases.append(self.runner.phase)
        self.contact.append((self.now_s, bool(self.vehicle.snapshot().pen_contact)))
        self.ticks += 1

    def until(self, done: Callable[[], bool], max_s: float = 90.0) -> None:
        end = self.now_s + max_s
        while not done():
            assert self.now_s < end, f"timed out in {self.runner.state}/{self.runner.phase}"
            self.tick()

    def assign(self, job_id: str = "j1") -> bool:
        reply = self.runner.handle_command(
            VehicleCommand(command="assign", job=JobAssignment(job_id=job_id, text="L")),
            self.now_s,
        )
        return reply.ok

    def failed(self) -> AgentReport:
        (report,) = [r for r in self.reports if r.event == "failed"]
        return report


def runaway(
    after_s: float, speed_mps: float = 1.0, up_to_m: float = 9.0
) -> Callable[[float], Vec3]:
    """From ``after_s`` (vehicle time) on, pushed along +x at ``speed_mps``, ``up_to_m`` far."""
    return lambda t: (min(max(0.0, t - after_s) * speed_mps, up_to_m), 0.0, 0.0)


def writing_starts_at() -> float:
    probe = Run()
    probe.assign()
    probe.until(lambda: probe.runner.phase == "write")
    return probe.now_s


def test_a_runaway_while_writing_lifts_the_brush_fails_the_job_and_backs_off() -> None:
    t_runaway = writing_starts_at() + 1.5  # pen down by then
    run = Run(push=runaway(t_runaway, speed_mps=1.0, up_to_m=0.3))
    assert run.assign()
    run.until(lambda: any(e.kind == "deviation" for e in run.events))
    tripped_s = run.now_s
    run.until(lambda: run.runner.phase == "ground")
    report = run.failed()
    assert report.error is not None and report.error.code == "deviation"
    assert report.retry_after_s is None  # ink on the board: final
    assert "above the bound 0.150 m" in report.error.message
    (event,) = [e for e in run.events if e.kind == "deviation"]
    assert event.level == "alert" and event.job_id == "j1"
    # 0.15 m at 1 m/s, then the 0.3 s window: the brush is off the board right after
    assert tripped_s - t_runaway == pytest.approx(0.15 + 0.3, abs=0.05)  # + a tick or two
    last_contact = max(t for t, c in run.contact if c and t < tripped_s + 2.0)
    assert last_contact - tripped_s < 0.05  # (the ideal vehicle "touches" again on the floor)
    assert not run.finished and run.commands == ["takeoff", "land"]
    (aborted,) = run.aborted  # what was flown, to measure: the report waits for its metrics
    flown = aborted.trace.flown
    assert aborted.report is report and flown.abort_reason == "deviation"
    assert 1.5 < flown.t_s[-1] < 4.0 and flown.pen_down.any()  # cut where it tripped
    assert flown.t_s[-1] == pytest.approx(tripped_s - writing_starts_at(), abs=0.02)
    assert 0.0 < report.progress < 1.0 and report.metrics is None
    assert (run.runner.state, run.vehicle.mode) == ("idle", "idle")
    reply = run.runner.handle_command(
        VehicleCommand(command="assign", job=JobAssignment(job_id="j2", text="A")), run.now_s
    )
    assert not reply.ok and reply.error is not None and reply.error.code == "deviation"
    run.until(lambda: run.now_s > tripped_s + 20.0)
    assert run.assign("j2")


def test_a_deviation_before_writing_hands_the_job_back_and_never_puts_the_brush_down() -> None:
    run = Run(push=runaway(0.0, speed_mps=0.5, up_to_m=0.3))  # pushed once it tracks setpoints
    run.assign()
    run.until(lambda: run.runner.phase == "ground" and bool(run.reports))
    report = run.failed()
    assert report.error is not None and report.error.code == "deviation"
    assert report.retry_after_s == 20.0  # back to the queue, the vehicle backs off
    assert "started" not in [r.event for r in run.reports] and "write" not in run.phases


def test_hold_policy_hovers_with_the_brush_up_then_returns_and_lands() -> None:
    t_runaway = writing_starts_at() + 1.5
    run = Run(safety=limits(abort_policy="hold", abort_hold_s=4.0),
              push=lambda t: (0.3 if t > t_runaway else 0.0, 0.0, 0.0))  # fmt: skip
    run.assign()
    run.until(lambda: run.runner.phase == "hover")
    hover_from = run.now_s
    assert run.vehicle.position_m_enu[2] >= CRUISE_Z
    run.until(lambda: run.runner.phase == "return")
    assert run.now_s - hover_from == pytest.approx(4.0, abs=0.05)
    run.until(lambda: run.runner.phase == "ground")
    assert run.runner.state == "idle" and run.failed().error.code == "deviation"  # type: ignore[union-attr]


def test_an_unsettled_start_is_flown_again_then_handed_back_without_ink() -> None:
    run = Run(push=lambda _t: (0.02, 0.0, 0.0))  # holds 2 cm off: never within 1 cm
    run.assign()
    run.until(lambda: run.runner.phase == "ground" and bool(run.reports))
    report = run.failed()
    assert report.error is not None and report.error.code == "not_settled"
    assert report.retry_after_s == 20.0 and "after 2 approaches" in report.error.message
    assert "20.0 mm from the start, outside the 10.0 mm tolerance" in report.error.message
    assert run.phases.count("transit") == 2 and run.phases.count("settle") == 2
    assert "write" not in run.phases and "started" not in [r.event for r in run.reports]
    assert [e.level for e in run.events if e.kind == "not_settled"] == ["warning"]


def test_a_vehicle_swinging_through_the_start_does_not_write() -> None:
    """2 cm swings of 2 s period cross the 1 cm tolerance for 0.33 s at a time: never held 1 s."""
    run = Run(push=lambda t: (0.02 * float(np.sin(np.pi * t)), 0.0, 0.0))
    run.assign()
    run.until(lambda: run.runner.phase == "ground" and bool(run.reports))
    report = run.failed()
    assert report.error is not None and report.error.code == "not_settled"
    assert "write" not in run.phases and "started" not in [r.event for r in run.reports]


def test_an_approach_that_ends_inside_the_tolerance_names_the_hold_it_fell_short_of() -> None:
    """Back within 1 cm 0.3 s before the last approach runs out: its distance passes the check,
    the time it held does not, and the message says so (not "error 4 mm, not within 10 mm")."""
    probe = Run(push=lambda _t: (0.02, 0.0, 0.0))
    probe.assign()
    probe.until(lambda: probe.phases.count("settle") == 2)  # the last approach begins to settle
    inside_from_s = probe.now_s + probe.safety.settle_timeout_s - 0.3
    run = Run(push=lambda t: (0.02 if t < inside_from_s else 0.004, 0.0, 0.0))
    run.assign()
    run.until(lambda: run.runner.phase == "ground" and bool(run.reports))
    message = run.failed().error.message  # type: ignore[union-attr]
    found = re.search(
        r"within ([\d.]+) mm of the start for ([\d.]+) s, short of the ([\d.]+) s", message
    )
    assert found is not None, message
    tolerance_mm, held_s, hold_s = (float(v) for v in found.groups())
    assert tolerance_mm == pytest.approx(run.safety.settle_tolerance_m * 1e3)
    assert hold_s == run.safety.settle_hold_s and held_s < hold_s
    assert held_s == pytest.approx(0.3, abs=2 * DT)
    assert "after 2 approaches of 3.0 s" in message and "write" not in run.phases


def test_an_unsettled_figure_is_never_shown_equal_to_the_bound_it_failed() -> None:
    safety = limits(settle_tolerance_m=0.01, settle_hold_s=1.0)
    outside = unsettled_reason(0.0100004, -math.inf, safety)
    assert outside == "10.0004 mm from the start, outside the 10.0000 mm tolerance"
    assert unsettled_reason(0.025, -math.inf, safety) == (
        "25.0 mm from the start, outside the 10.0 mm tolerance"
    )
    inside = unsettled_reason(0.0099, 0.999, safety)
    assert inside == "within 10.0 mm of the start for 0.999 s, short of the 1.000 s to hold"


def test_the_brush_goes_down_only_after_the_start_is_held() -> None:
    run = Run()
    run.assign()
    run.until(lambda: run.runner.phase == "settle")
    settle_from_s = run.now_s
    run.until(lambda: run.runner.phase == "write")
    assert run.now_s - settle_from_s == pytest.approx(run.safety.settle_hold_s, abs=2 * DT)


def test_a_second_approach_that_settles_writes() -> None:
    settled_after_s = writing_starts_at() + 3.5  # 2 cm off until the first settle timed out
    run = Run(push=lambda t: (0.02 if t < settled_after_s else 0.0, 0.0, 0.0))
    run.assign()
    run.until(lambda: run.runner.phase == "ground" and bool(run.finished))
    assert run.phases.count("transit") == 2 and "write" in run.phases
    assert [r.event for r in run.reports] == ["started"]


def test_a_plan_that_leaves_the_fence_is_refused_before_take_off() -> None:
    run = Run(samples=line_samples(y_m=1.5))  # 1.5 m north of the board centre: outside
    run.assign()
    for _ in range(5):
        run.tick()
    report = run.failed()
    assert report.error is not None and report.error.code == "geofence"
    assert "leaves the vehicle's geofence" in report.error.message
    assert run.commands == [] and run.vehicle.mode == "idle" and run.runner.state == "idle"
    assert [e.kind for e in run.events] == ["geofence"]


def test_a_vehicle_outside_its_fence_holds_then_lands_there_and_stays_in_fault() -> None:
    t_runaway = writing_starts_at() + 1.5
    safety = limits(deviation=DeviationLimit(5.0, 0.3), fence_hold_s=1.0)  # fence acts first
    run = Run(safety=safety, push=runaway(t_runaway, speed_mps=1.0))
    run.assign()
    run.until(lambda: run.runner.phase == "fence_hold")
    breach_s = run.now_s
    (event,) = [e for e in run.events if e.kind == "geofence"]
    assert event.level == "alert"
    found = re.search(r"outside its geofence by ([\d.]+) mm", event.message)
    assert found is not None and 0.0 < float(found.group(1)) <= 1e3 * DT  # a tick at 1 m/s
    assert "at (1.21, 0.00, 0.35) m" in event.message  # caught at the fence's edge, x = 1.21
    run.until(lambda: run.runner.phase == "land")
    assert run.now_s - breach_s == pytest.approx(1.0, abs=0.05)
    run.until(lambda: run.runner.phase == "stopped")
    assert run.runner.state == "fault" and "geofence" in run.runner.message
    report = run.failed()
    assert report.error is not None and report.error.code == "geofence"
    assert run.commands == ["takeoff", "land"] and run.vehicle.mode == "idle"
    assert not run.assign("j2")


def test_mode_changes_and_faults_become_events() -> None:
    run = Run()
    base = run.vehicle.snapshot()
    for mode, fault in [("STABILIZE", None), ("GUIDED", None), ("GUIDED", None),
                        ("LOITER", "mode changed to LOITER")]:  # fmt: skip
        run.tick(replace(base, autopilot_mode=mode, fault=fault))
    kinds = [(e.kind, e.level, e.message) for e in run.events]
    assert kinds == [
        ("vehicle_mode", "info", "uav1 autopilot mode STABILIZE"),
        ("vehicle_mode", "info", "uav1 autopilot mode STABILIZE -> GUIDED"),
        ("vehicle_mode", "info", "uav1 autopilot mode GUIDED -> LOITER"),
        ("vehicle_fault", "alert", "uav1 fault: mode changed to LOITER"),
    ]


def test_done_only_within_the_writing_bounds() -> None:
    flown = recorded_trace("j1", 1, np.array([0.0, 1.0]), np.zeros((2, 3)), np.zeros((2, 3)),
                           np.zeros((2, 3)), np.array([True, True]), None)  # fmt: skip
    bounds = WritingBounds(rmse_pen_down_max_m=0.05, iou_min=0.3)

    def metrics(rmse: float, iou: float | None) -> JobMetrics:
        return JobMetrics(rmse_pen_down_m=rmse, rmse_m=rmse, max_error_m=rmse, iou=iou,
                          duration_s=1.0)  # fmt: skip

    assert result_report("uav1", flown, metrics(0.01, 0.8), bounds).event == "done"
    assert result_report("uav1", flown, metrics(0.01, None), bounds).event == "done"
    for bad, words in [(metrics(398.7, 0.0), "pen-down RMSE 398.7000 m above 0.0500 m"),
                       (metrics(0.01, 0.2), "ink IoU 0.200 below 0.300"),
                       (metrics(float("nan"), 0.9), "RMSE nan")]:  # fmt: skip
        report = result_report("uav1", flown, bad, bounds)
        assert report.event == "failed" and report.error is not None
        assert report.error.code == "writing_bounds" and words in report.error.message
        assert report.metrics == bad and report.retry_after_s is None
    unmeasured = result_report("uav1", flown, None, bounds)
    assert unmeasured.event == "failed" and unmeasured.error.code == "unmeasured"  # type: ignore[union-attr]
