"""The phases of a job runner that fly the vehicle (pure): moves, hover, settling, writing.

:class:`RunnerPhases` holds the runner's state and advances it once per control period; the job
runner (``vehicle_agent/job_runner.py``) adds the commands, the interruptions and the aborts.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Literal

from bus.messages import AgentReport, Telemetry, VehicleStateName, VehicleStatus
from vehicle_agent.backends.base import Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.end_reasons import ended_report
from vehicle_agent.motion import Move, plan_move
from vehicle_agent.runner_io import (
    AbortedJob,
    BackendCommand,
    RunnerConfig,
    RunnerEvent,
    telemetry_message,
)
from vehicle_agent.runner_job import RunningJob
from vehicle_agent.safety.guard import SafetyGuard, figures_apart
from vehicle_agent.safety.limits import SafetyLimits
from vehicle_agent.trace import JobTrace

Level = Literal["info", "warning", "alert"]
ABORT_LIFT_M = 0.1
"""After a safety abort the brush is lifted this much higher than the pen-up height, in [m]."""
ABORT_CEILING_GAP_M = 0.1
"""...but kept this far below the fence's ceiling, in [m]."""
POLICY_ABORTS = frozenset({"deviation", "not_settled"})
"""Aborts after which the vehicle follows ``safety.abort_policy`` (hold or land)."""


class RunnerPhases:
    """State of one vehicle's runner and the phases that move it (see the module docstring)."""

    def __init__(self, config: RunnerConfig) -> None:
        self.config = config
        self.safety = config.safety
        self.guard = SafetyGuard(config.safety)
        self.state: VehicleStateName = "idle"
        self.message = ""
        self.phase = "ground"
        """Finer step inside ``state``: ground, preflight, climb, wait_plan, transit, settle,
        write, lift, hover, return, fence_hold, land, stopped."""
        self._job: RunningJob | None = None
        self._abort: str | None = None
        self._after_landing: VehicleStateName = "idle"
        self._move: Move | None = None
        self._legs: list[Vec3] = []
        self._last_move_s = 0.0
        """Agent time in [s] of the last tick that followed a pen-up move."""
        """Ends of the legs of the current pen-up move still to go after ``_move``."""
        self._hold_m_enu: Vec3 | None = None
        self._backend_command: BackendCommand | None = None
        self._reports: list[AgentReport] = []
        self._aborted: AbortedJob | None = None
        """A job broken off after its writing began, for this tick's actions."""
        self._events: list[RunnerEvent] = []
        self._orchestrator_alive = False
        self.may_begin_writing = True
        """Whether the job lease lets the brush go down now (set by the service before each
        tick): a vehicle that has settled at the start holds it until its *ready* report is
        acknowledged (``vehicle_agent/lease.py``), and while the orchestrator's token is gone."""
        self._next_telemetry_s = -math.inf
        self._last_setpoint: Setpoint | None = None
        """The last setpoint given (phases with a reference), where interruptions start from."""
        self._tracked: Setpoint | None = None
        """The setpoint of the last tick (None: the backend's mode flew), for the guard."""
        self._settle_until_s = 0.0
        self._settled_since_s: float | None = None
        """Since when in [s] the vehicle has been inside the settle tolerance (None: outside)."""
        self._hover_until_s = math.inf
        self._retry_at_s = -math.inf
        self._retry_code = "takeoff_refused"
        self._retry_reason = ""
        self._retry_backoff_s = config.takeoff_retry_s
        self._seen_mode: str | None = None
        self._seen_fault: str | None = None
        self.preflight: str | None = None
        """Why the vehicle cannot take off now (its preflight's first failing check, or its
        autopilot's words), published in the status; None: it can."""
        self.clock_offset_s: float | None = None
        """The agent's clock minus the orchestrator's in [s], as last measured (set by the
        service; None: not yet)."""
        self._preflight_since_s = 0.0
        """Agent time in [s] since when ``preflight`` has been set."""
        self._planned_at_s = 0.0
        """Agent time in [s] the current job's plan came back (the pre-arm wait counts from it)."""
        self._now_s = 0.0

    @property
    def job_id(self) -> str | None:
        """The job this vehicle is working on (until it has landed after it)."""
        return None if self._job is None else self._job.job_id

    @property
    def ready_to_write_s(self) -> float | None:
        """While the vehicle settles at the start of its writing: the planned writing in show
        [s], which its *ready* report carries (None otherwise)."""
        job = self._job
        if self.phase != "settle" or job is None or job.prepared is None:
            return None
        return job.prepared.samples.duration_s

    def _abort_job(
        self, code: str, message: str, lift_from: Vec3, *, level: Level = "alert"
    ) -> None:
        """A safety abort (the job runner's)."""
        raise NotImplementedError

    def _lift(self, start: Vec3, *, extra_m: float = 0.0) -> None:
        """Straight up to the pen-up height (``extra_m`` higher after a safety abort, within the
        fence's ceiling)."""
        top = self.config.cruise_z_m + extra_m
        fence = self.safety.fence
        if fence is not None:
            top = min(top, max(self.config.cruise_z_m, fence.ceiling_z_m - ABORT_CEILING_GAP_M))
        lifted = (start[0], start[1], max(start[2], top))
        if not self.config.airborne:
            lifted = start  # a ground vehicle lifts its pen where it stands
        self._start_move(start, lifted, "lift", "returning")

    def _event(self, level: Level, kind: str, message: str) -> None:
        self._events.append(RunnerEvent(level, kind, message, self.job_id))

    def _advance(self, snap: VehicleSnapshot, now_s: float) -> Setpoint | None:
        phase = self.phase
        if phase in ("ground", "preflight", "stopped", "climb", "land"):
            return self._passive(snap)
        if phase == "wait_plan":
            if self._job is not None and self._job.prepared is not None:
                self._start_transit(self._current_reference())
            return self._reference_now(now_s)
        if phase in ("hover", "fence_hold"):
            return self._hover(now_s)
        if phase == "settle":
            return self._settle(snap, now_s)
        if phase == "write":
            assert self._job is not None
            return self._job.setpoint(now_s)
        assert self._move is not None
        self._wait_for_vehicle(snap, now_s)
        setpoint = self._move.setpoint(now_s)
        if self._move.done(now_s) and self._legs:
            self._next_leg()
        elif self._move.done(now_s):
            self._move_finished(snap)
            if self.phase == "land":
                return None  # the backend's landing mode flies from here
        return setpoint

    def _wait_for_vehicle(self, snap: VehicleSnapshot, now_s: float) -> None:
        """Hold a pen-up move's clock for this tick while the vehicle is too far behind it
        (``transit_wait_m``)."""
        wait_m, move = self.config.transit_wait_m, self._move
        tick_s, self._last_move_s = now_s - self._last_move_s, now_s
        if wait_m is None or move is None or move.done(now_s) or tick_s <= 0.0:
            return
        ahead = move.setpoint(now_s).position_m_enu
        if math.dist(ahead[:2], snap.position_m_enu[:2]) > wait_m:
            self._move = replace(move, t0_s=move.t0_s + tick_s)

    def _passive(self, snap: VehicleSnapshot) -> Setpoint | None:
        """Phases where the backend's own mode flies: on the ground, climbing, landing."""
        airborne_hold = snap.mode == "hold" and not snap.on_ground
        if self.phase == "climb" and airborne_hold and self._backend_command is None:
            # where it climbed: above home, or above where an emergency stop dropped it
            x_m, y_m, _ = snap.position_m_enu
            top = (x_m, y_m, self.config.hover_home_m_enu[2])
            self._hold_m_enu = top
            self._retry_backoff_s = self.config.takeoff_retry_s  # it flies: forget refusals
            if self._abort is not None:
                self._start_return(top)
            else:
                self.phase = "wait_plan"
                if self._job is not None and self._job.prepared is not None:
                    # from where the climb left it, within the take-off's tolerance of top
                    self._start_transit(snap.position_m_enu)
            return self._reference_now(self._now_s)
        if self.phase == "land" and snap.on_ground and snap.mode == "idle":
            stopped = self._after_landing == "fault"
            self.state, self.phase = self._after_landing, "stopped" if stopped else "ground"
            if not stopped:
                self.message = "landed" if self.state == "landed" else ""
            self._job = None
            self._abort = None
        return None

    def _hover(self, now_s: float) -> Setpoint | None:
        """Hold in place until the hover ends: then return and land (or land right here)."""
        if now_s >= self._hover_until_s:
            if self.phase == "fence_hold":
                self._backend_command = ("land", None)
                self.phase, self.state = "land", "landing"
                return None  # the backend's landing mode flies from here
            else:
                self._start_return(self._current_reference())
        return self._hold()

    def _settle(self, snap: VehicleSnapshot, now_s: float) -> Setpoint:
        """Hold the start of the plan until the vehicle has stayed there ``settle_hold_s``; fly
        the approach again if it does not in time; hand the job back when no approach settles."""
        job = self._job
        assert job is not None and self._hold_m_enu is not None
        error = math.dist(snap.position_m_enu, self._hold_m_enu)
        safety = self.safety
        if error > safety.settle_tolerance_m:
            self._settled_since_s = None
        elif self._settled_since_s is None:
            self._settled_since_s = now_s
        held_s = -math.inf if self._settled_since_s is None else now_s - self._settled_since_s
        if held_s >= safety.settle_hold_s:
            if not (self.may_begin_writing and self._orchestrator_alive):  # wait for it
                self._settle_until_s = max(self._settle_until_s, now_s + safety.settle_hold_s)
                return self._hold()
            self._begin_writing(job)
            return job.setpoint(now_s)
        if now_s < self._settle_until_s:
            return self._hold()
        why = unsettled_reason(error, held_s, safety)
        if job.approaches < safety.settle_attempts:
            self.message = f"not settled ({why}): flying the approach again"
            self._start_transit(snap.position_m_enu)
            return self._reference_now(now_s)
        message = (
            f"not settled after {job.approaches} approaches of "
            f"{safety.settle_timeout_s:.1f} s: {why}"
        )
        self._abort_job("not_settled", message, self._hold_m_enu, level="warning")
        assert self._move is not None
        return self._move.setpoint(now_s)

    def _reference_now(self, now_s: float) -> Setpoint:
        """The reference of a phase that was just entered."""
        if self._move is not None and self.phase in ("transit", "lift", "return"):
            return self._move.setpoint(now_s)
        return self._hold()

    def _hold(self) -> Setpoint:
        return Setpoint(position_m_enu=self._hold_m_enu or self.config.hover_home_m_enu)

    def _start_transit(self, start_m_enu: Vec3) -> None:
        assert self._job is not None and self._job.prepared is not None
        prepared = self._job.prepared
        first = (prepared.command_samples or prepared.samples).position_m_enu[0]
        end = (float(first[0]), float(first[1]), float(first[2]))
        self._start_move(start_m_enu, end, "transit", "taking_off")

    def _start_return(self, start_m_enu: Vec3) -> None:
        self._start_move(start_m_enu, self.config.hover_home_m_enu, "return", "returning")

    def _start_move(self, start: Vec3, end: Vec3, phase: str, state: VehicleStateName) -> None:
        """A pen-up move from ``start`` to ``end`` in the legs of the kind's route."""
        first, *rest = self.config.legs(start, end)
        self._legs = rest
        self._start_leg(start, first)
        self.phase, self.state = phase, state

    def _start_leg(self, start: Vec3, end: Vec3) -> None:
        cfg = self.config
        self._move = plan_move(
            start, end, self._now_s, v_max_mps=cfg.v_max_mps, a_max_mps2=cfg.a_max_mps2
        )
        self._hold_m_enu = end

    def _next_leg(self) -> None:
        assert self._move is not None
        self._start_leg(self._move.end_m_enu, self._legs.pop(0))

    def _move_finished(self, snap: VehicleSnapshot) -> None:
        if self.phase == "transit":
            assert self._job is not None
            self._job.approaches += 1
            self.phase = "settle"
            self._settle_until_s = self._now_s + self.safety.settle_timeout_s
            self._settled_since_s = None
        elif self.phase == "lift":
            self._after_lift()
        elif self.phase == "return":
            self._backend_command = ("land", None)
            self.phase, self.state = "land", "landing"

    def _after_lift(self) -> None:
        if self._abort in POLICY_ABORTS and self.safety.abort_policy == "hold":
            self._hover_until_s = self._now_s + self.safety.abort_hold_s
            self.phase, self.state = "hover", "returning"
        else:
            self._start_return(self._current_reference())

    def _current_reference(self) -> Vec3:
        if self._last_setpoint is not None and self.phase not in ("climb", "ground"):
            return self._last_setpoint.position_m_enu
        return self._hold_m_enu or self.config.hover_home_m_enu

    # --- writing -------------------------------------------------------------------------------
    def _begin_writing(self, job: RunningJob) -> None:
        assert job.prepared is not None
        job.started_s = self._now_s
        job.next_progress_s = self._now_s + self.config.progress_period_s
        self.phase, self.state = "write", "writing"
        duration_s = job.prepared.samples.duration_s
        self._reports.append(
            job.report(self.config.vehicle_id, "started", planned_duration_s=duration_s)
        )

    def _end_job(self, job: RunningJob, reason: str, report: AgentReport | None = None) -> None:
        """``job`` stops before its end (``reason``): once its writing has begun, what was flown
        goes out with ``report`` (:class:`AbortedJob`: measured first, its report then carries
        the metrics; None: an ``ended`` report is made of it, ``vehicle_agent/job_end.py``);
        before, ``report`` goes at once, or else an ``ended`` report that nothing was written
        (``vehicle_agent/end_reasons.py``). A job written to its end has its result from the
        finished job's measure already."""
        trace = job.broken_off(reason)
        if trace is not None:
            self._aborted = AbortedJob(trace, report)
        elif job.written:
            return
        elif report is not None:
            self._reports.append(report)
        else:  # nothing of its writing flown: said so, with no figure of a writing
            vid = self.config.vehicle_id
            ended = ended_report(vid, job.job_id, reason, 0.0, None, pen_came_down=False)
            self._reports.append(ended)

    def _write_tick(
        self, snap: VehicleSnapshot, now_s: float, setpoint: Setpoint
    ) -> JobTrace | None:
        job = self._job
        assert job is not None
        written = job.record(snap, now_s)
        if now_s >= job.next_progress_s and not written:
            job.next_progress_s = now_s + self.config.progress_period_s
            self._reports.append(job.report(self.config.vehicle_id, "progress"))
        if not written:
            return None
        self.message = f"job {job.job_id} written"
        self._start_return(setpoint.position_m_enu)
        return job.finish()

    # --- outputs -------------------------------------------------------------------------------
    def _telemetry(
        self, snap: VehicleSnapshot, setpoint: Setpoint | None, now_s: float
    ) -> Telemetry | None:
        period = self.config.telemetry_period_s
        if now_s < self._next_telemetry_s - 1e-9:
            return None
        self._next_telemetry_s += period
        if self._next_telemetry_s <= now_s:  # first message, or the loop fell behind
            self._next_telemetry_s = now_s + period
        progress = 0.0 if self._job is None else self._job.progress
        return telemetry_message(
            self.config.vehicle_id,
            self.state,
            snap,
            setpoint,
            now_s,
            job_id=self.job_id,
            progress=progress,
        )

    def status(self, incarnation: str | None = None) -> VehicleStatus:
        """The vehicle's status message as of now (publish it when it changes); ``incarnation``:
        the agent's start it goes out from (``VehicleStatus.incarnation``)."""
        return VehicleStatus(
            vehicle_id=self.config.vehicle_id,
            kind=self.config.kind,
            state=self.state,
            board_id=self.config.board_id,
            job_id=self.job_id,
            message=self.message,
            incarnation=incarnation,
            preflight=self.preflight or "",
            clock_offset_ms=None if (off_s := self.clock_offset_s) is None else round(1e3 * off_s),
        )


def unsettled_reason(error_m: float, held_s: float, safety: SafetyLimits) -> str:
    """Why the vehicle has not settled at the start when its approach runs out, in the figure its
    check failed: its distance ``error_m`` while outside the tolerance, else how long ``held_s``
    it has been inside (it must stay ``settle_hold_s`` without a break). Its distance alone, once
    back inside, would read as a success."""
    if error_m > safety.settle_tolerance_m:
        error, tolerance = figures_apart(error_m * 1e3, safety.settle_tolerance_m * 1e3)
        return f"{error} mm from the start, outside the {tolerance} mm tolerance"
    held, hold = figures_apart(held_s, safety.settle_hold_s)
    return (
        f"within {safety.settle_tolerance_m * 1e3:.1f} mm of the start for {held} s, "
        f"short of the {hold} s to hold"
    )
