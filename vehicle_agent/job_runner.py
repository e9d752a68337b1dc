"""What one vehicle does, decided in pure code: commands and ticks in, setpoints and reports out.

The service (``vehicle_agent/service.py``) feeds a :class:`JobRunner` with the orchestrator's
commands, the orchestrator's presence and one backend snapshot per control period, and carries out
the :class:`TickActions` it returns. Nothing here reads a clock or touches the network.

Life of a job (``VehicleStatus.state``)::

    idle -> taking_off -> writing -> returning -> landing -> idle
            (climb, plan, transit)   (to hover above home, then land)

Interruptions while a job is running lift the brush first (straight up to the pen-up height), then:
cancel -> return and land -> idle; operator land -> return and land -> landed; orchestrator lost ->
hover in place, and when it comes back, or after ``loss_land_after_s``, return and land; estop ->
motors off, ``fault``. A vehicle fault reported by the backend ends in ``fault`` as well.

Reports: ``started``, ``progress`` and ``done`` for a job flown to its end; ``failed`` when the
job itself cannot be written (it cannot be planned), or, with ``retry_after_s``, when the vehicle
refused to take off (pre-arm checks): the job goes back to the queue and the vehicle stays idle,
taking no job until then. An interrupted job is abandoned without a
report: the status drops its ``job_id`` at once, and the orchestrator, which asked for the
interruption or was away, puts the job back in the queue for another vehicle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

from bus.messages import (
    AgentReport,
    CommandReply,
    ErrorInfo,
    JobAssignment,
    Telemetry,
    VehicleCommand,
    VehicleStateName,
    VehicleStatus,
)
from vehicle_agent.backends.base import Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.motion import Move, plan_move
from vehicle_agent.runner_io import (
    ACTIVE_PHASES,
    BackendCommand,
    PreparedJob,
    RunnerConfig,
    TickActions,
    done_report,
    refuse,
    sample_at,
    takeoff_refused_report,
    telemetry_message,
    vec3,
)
from vehicle_agent.trace import FlownTrace, TraceRecorder

__all__ = [
    "ACTIVE_PHASES",
    "BackendCommand",
    "JobRunner",
    "PreparedJob",
    "RunnerConfig",
    "TickActions",
    "done_report",
    "sample_at",
]


@dataclass
class _Job:
    assignment: JobAssignment
    prepared: PreparedJob | None = None
    plan_requested: bool = False
    started_s: float | None = None
    recorder: TraceRecorder = field(default_factory=TraceRecorder)
    progress: float = 0.0
    next_progress_s: float = 0.0
    planned_now: Setpoint | None = None
    """The plan's sample at this tick: set by ``_write_setpoint``, recorded by ``_write_tick``."""


class JobRunner:
    """The decision logic of one vehicle agent (see the module docstring)."""

    def __init__(self, config: RunnerConfig) -> None:
        self.config = config
        self.state: VehicleStateName = "idle"
        self.message = ""
        self.phase = "ground"
        """Finer step inside ``state``: ground, climb, wait_plan, transit, settle, write, lift,
        hover, return, land, stopped."""
        self._job: _Job | None = None
        self._abort: str | None = None
        self._after_landing: VehicleStateName = "idle"
        self._move: Move | None = None
        self._hold_m_enu: Vec3 | None = None
        self._backend_command: BackendCommand | None = None
        self._reports: list[AgentReport] = []
        self._orchestrator_alive = False
        self._lost_since_s: float | None = None
        self._next_telemetry_s = -math.inf
        self._last_setpoint: Setpoint | None = None
        self._settle_until_s = 0.0
        self._retry_at_s = -math.inf
        self._retry_backoff_s = config.takeoff_retry_s

    # --- inputs --------------------------------------------------------------------------------
    @property
    def job_id(self) -> str | None:
        """The job this vehicle is working on (until it has landed after it)."""
        return None if self._job is None else self._job.assignment.job_id

    @property
    def orchestrator_alive(self) -> bool:
        return self._orchestrator_alive

    def handle_command(self, command: VehicleCommand, now_s: float) -> CommandReply:
        """Answer an orchestrator command; any motion it needs starts at the next tick."""
        if command.command == "assign":
            return self._assign(command.job, now_s)
        if command.command == "cancel":
            return self._cancel(command.job_id)
        if command.command == "land":
            return self._land()
        return self._estop()

    def set_orchestrator_alive(self, alive: bool, now_s: float) -> None:
        """The orchestrator's liveliness token appeared (True) or disappeared (False)."""
        if alive == self._orchestrator_alive:
            return
        self._orchestrator_alive = alive
        if not alive:
            self._lost_since_s = now_s
            if self.phase in ACTIVE_PHASES:
                self._interrupt("orchestrator_lost", "orchestrator lost: brush lifted, hovering")
            return
        self._lost_since_s = None
        if self.phase == "hover":
            self.message = "orchestrator back: returning home"
            self._start_return(self._current_reference())

    def plan_ready(self, prepared: PreparedJob) -> None:
        """The planner finished the current job's trajectory."""
        if self._job is not None and self._job.assignment.job_id == prepared.job_id:
            self._job.prepared = prepared

    def plan_failed(self, job_id: str, error: ErrorInfo) -> None:
        """The job could not be laid out or planned: report it failed and come back."""
        if self._job is None or self._job.assignment.job_id != job_id or self._abort:
            return
        self._fail(error)
        self.message = f"cannot plan: {error.message}"
        self._abort = "plan_failed"
        self._job = None
        if self.phase in ("wait_plan", "transit", "settle"):
            self._start_return(self._current_reference())

    def takeoff_refused(self, reason: str, now_s: float) -> None:
        """The vehicle declined to take off (its pre-arm checks failed) and is still on the ground,
        healthy: hand the job back (``failed`` with ``retry_after_s``) and take no job for a
        while, twice as long after each refusal in a row."""
        if self.phase != "climb":
            return
        backoff = self._retry_backoff_s
        self._retry_backoff_s = min(2.0 * backoff, self.config.takeoff_retry_max_s)
        self._retry_at_s = now_s + backoff
        if self._job is not None and self._abort is None:
            job_id = self._job.assignment.job_id
            vid = self.config.vehicle_id
            self._reports.append(takeoff_refused_report(vid, job_id, reason, backoff))
        self.state, self.phase = self._after_landing, "ground"
        self.message = f"take-off refused: {reason} (next try in {backoff:.0f} s)"
        self._job, self._abort, self._move = None, None, None
        self._backend_command = None

    # --- commands ------------------------------------------------------------------------------
    def _assign(self, job: JobAssignment | None, now_s: float) -> CommandReply:
        if job is None:
            return refuse("missing_job", "assign needs a job")
        if self._job is not None and self._job.assignment.job_id == job.job_id:
            return CommandReply(ok=True, message="already working on it")
        if self.phase != "ground" or self.state not in ("idle", "landed"):
            return refuse("busy", f"vehicle is {self.state}", field="job")
        if now_s < self._retry_at_s:
            wait_s = self._retry_at_s - now_s
            return refuse("takeoff_refused", f"{self.message}; {wait_s:.0f} s to wait", field="job")
        self._orchestrator_alive = True
        self._lost_since_s = None
        self._job = _Job(assignment=job)
        self._abort = None
        self._after_landing = "idle"
        self.state, self.phase, self.message = "taking_off", "climb", f"job {job.job_id}"
        self._backend_command = ("takeoff", self.config.hover_home_m_enu)
        return CommandReply(ok=True, message=f"took job {job.job_id}")

    def _cancel(self, job_id: str | None) -> CommandReply:
        if self._job is None or (job_id is not None and job_id != self.job_id):
            return CommandReply(ok=True, message="no such job running here")
        job_id = self.job_id
        if self.phase in ACTIVE_PHASES:
            self._interrupt("cancelled", "job cancelled: returning home")
        return CommandReply(ok=True, message=f"cancelled {job_id}")

    def _land(self) -> CommandReply:
        if self.phase == "stopped":
            return refuse("stopped", "vehicle is stopped")
        self._after_landing = "landed"
        if self.phase == "ground":
            self.state, self.message = "landed", "landed by operator"
        elif self.phase in ACTIVE_PHASES:
            self._interrupt("landed_by_operator", "landing on operator command")
        elif self.phase == "hover":
            self._start_return(self._current_reference())
        return CommandReply(ok=True, message="landing")

    def _estop(self) -> CommandReply:
        self._backend_command = ("estop", None)
        self._stop("emergency stop")
        return CommandReply(ok=True, message="motors off")

    def _stop(self, message: str) -> None:
        self.state, self.phase, self.message = "fault", "stopped", message
        self._move = None
        self._job = None

    # --- interruptions -------------------------------------------------------------------------
    def _interrupt(self, reason: str, message: str) -> None:
        """Stop writing the current job: lift the brush; what follows depends on ``reason``."""
        self._abort = reason
        self.message = message
        self._job = None  # abandoned: the orchestrator requeues it (it asked, or it was gone)
        if self.phase == "climb":
            return  # lifted already; _advance decides once the climb is over
        ref = self._current_reference()
        lifted = (ref[0], ref[1], max(ref[2], self.config.cruise_z_m))
        self._start_move(ref, lifted, "lift", "returning")

    def _fail(self, error: ErrorInfo) -> None:
        assert self._job is not None
        self._reports.append(
            AgentReport(
                vehicle_id=self.config.vehicle_id,
                job_id=self._job.assignment.job_id,
                event="failed",
                progress=self._job.progress,
                error=error,
            )
        )

    # --- the tick ------------------------------------------------------------------------------
    def step(self, snapshot: VehicleSnapshot, now_s: float) -> TickActions:
        """Decide this control period from the vehicle state at its start (agent time ``now_s``)."""
        self._now_s = now_s
        if snapshot.fault is not None and self.phase != "stopped":
            self._stop(f"vehicle fault: {snapshot.fault}")
        plan_request = self._take_plan_request()
        finished = None
        setpoint = self._advance(snapshot, now_s)
        if self.phase == "write" and self._job is not None:
            finished = self._write_tick(snapshot, now_s, setpoint)
        if setpoint is not None:
            self._last_setpoint = setpoint
        actions = TickActions(
            backend_command=self._backend_command,
            setpoint=setpoint,
            plan_request=plan_request,
            reports=tuple(self._reports),
            telemetry=self._telemetry(snapshot, setpoint, now_s),
            finished=finished,
        )
        self._backend_command = None
        self._reports = []
        return actions

    def _take_plan_request(self) -> JobAssignment | None:
        if self._job is None or self._job.plan_requested or self.phase == "stopped":
            return None
        self._job.plan_requested = True
        return self._job.assignment

    def _advance(self, snap: VehicleSnapshot, now_s: float) -> Setpoint | None:
        phase = self.phase
        if phase in ("ground", "stopped", "climb", "land"):
            return self._passive(snap)
        if phase == "wait_plan":
            if self._job is not None and self._job.prepared is not None:
                self._start_transit()
            return self._reference_now(now_s)
        if phase == "hover":
            lost_for = now_s - (self._lost_since_s if self._lost_since_s is not None else now_s)
            if lost_for >= self.config.loss_land_after_s:
                self._after_landing = "landed"
                self.message = "orchestrator lost: landing"
                self._start_return(self._current_reference())
            return self._hold()
        if phase == "settle":
            error = math.dist(snap.position_m_enu, self._hold_m_enu or snap.position_m_enu)
            if error <= self.config.settle_tolerance_m or now_s >= self._settle_until_s:
                self._begin_writing()
                return self._write_setpoint(now_s)
            return self._hold()
        if phase == "write":
            return self._write_setpoint(now_s)
        assert self._move is not None
        setpoint = self._move.setpoint(now_s)
        if self._move.done(now_s):
            self._move_finished()
            if self.phase == "land":
                return None  # the backend's landing mode flies from here
        return setpoint

    def _passive(self, snap: VehicleSnapshot) -> Setpoint | None:
        """Phases where the backend's own mode flies: on the ground, climbing, landing."""
        airborne_hold = snap.mode == "hold" and not snap.on_ground
        if self.phase == "climb" and airborne_hold and self._backend_command is None:
            self._hold_m_enu = self.config.hover_home_m_enu
            self._retry_backoff_s = self.config.takeoff_retry_s  # it flies: forget refusals
            if self._abort is not None:
                self._start_return(self.config.hover_home_m_enu)
            else:
                self.phase = "wait_plan"
                if self._job is not None and self._job.prepared is not None:
                    self._start_transit()
            return self._reference_now(self._now_s)
        if self.phase == "land" and snap.on_ground and snap.mode == "idle":
            self.state, self.phase = self._after_landing, "ground"
            self.message = "landed" if self.state == "landed" else ""
            self._job = None
            self._abort = None
        return None

    def _reference_now(self, now_s: float) -> Setpoint:
        """The reference of a phase that was just entered."""
        if self._move is not None and self.phase in ("transit", "lift", "return"):
            return self._move.setpoint(now_s)
        return self._hold()

    def _hold(self) -> Setpoint:
        return Setpoint(position_m_enu=self._hold_m_enu or self.config.hover_home_m_enu)

    def _start_transit(self) -> None:
        assert self._job is not None and self._job.prepared is not None
        prepared = self._job.prepared
        first = (prepared.command_samples or prepared.samples).position_m_enu[0]
        self._start_move(self._current_reference(), vec3(first), "transit", "taking_off")

    def _start_return(self, start_m_enu: Vec3) -> None:
        self._start_move(start_m_enu, self.config.hover_home_m_enu, "return", "returning")

    def _start_move(self, start: Vec3, end: Vec3, phase: str, state: VehicleStateName) -> None:
        cfg = self.config
        self._move = plan_move(
            start, end, self._now_s, v_max_mps=cfg.v_max_mps, a_max_mps2=cfg.a_max_mps2
        )
        self._hold_m_enu = end
        self.phase, self.state = phase, state

    def _move_finished(self) -> None:
        if self.phase == "transit":
            self.phase = "settle"
            self._settle_until_s = self._now_s + self.config.settle_timeout_s
        elif self.phase == "lift":
            if self._abort == "orchestrator_lost" and not self._orchestrator_alive:
                self.phase, self.state = "hover", "returning"
            else:
                self._start_return(self._current_reference())
        elif self.phase == "return":
            self._backend_command = ("land", None)
            self.phase, self.state = "land", "landing"

    def _current_reference(self) -> Vec3:
        if self._last_setpoint is not None and self.phase not in ("climb", "ground"):
            return self._last_setpoint.position_m_enu
        return self._hold_m_enu or self.config.hover_home_m_enu

    # --- writing -------------------------------------------------------------------------------
    def _begin_writing(self) -> None:
        job = self._job
        assert job is not None and job.prepared is not None
        job.started_s = self._now_s
        job.next_progress_s = self._now_s + self.config.progress_period_s
        self.phase, self.state = "write", "writing"
        self._reports.append(
            AgentReport(
                vehicle_id=self.config.vehicle_id,
                job_id=job.assignment.job_id,
                event="started",
                planned_duration_s=job.prepared.samples.duration_s,
            )
        )

    def _write_setpoint(self, now_s: float) -> Setpoint:
        job = self._job
        assert job is not None and job.prepared is not None and job.started_s is not None
        prepared = job.prepared
        t_rel_s = now_s - job.started_s
        job.planned_now = sample_at(prepared.samples, t_rel_s)
        if prepared.command_samples is None:
            return job.planned_now
        # The body is commanded along the prepared reference; the pen state is the plan's.
        commanded = sample_at(prepared.command_samples, t_rel_s)
        return replace(commanded, pen_down=job.planned_now.pen_down)

    def _write_tick(
        self, snap: VehicleSnapshot, now_s: float, setpoint: Setpoint | None
    ) -> FlownTrace | None:
        job = self._job
        assert job is not None and job.prepared is not None and job.started_s is not None
        assert setpoint is not None and job.planned_now is not None
        t_rel = now_s - job.started_s
        duration = job.prepared.samples.duration_s
        job.recorder.add(t_rel, snap, job.planned_now)
        job.progress = min(t_rel / duration, 1.0) if duration > 0 else 1.0
        if now_s >= job.next_progress_s and t_rel < duration:
            job.next_progress_s = now_s + self.config.progress_period_s
            self._reports.append(
                AgentReport(
                    vehicle_id=self.config.vehicle_id,
                    job_id=job.assignment.job_id,
                    event="progress",
                    progress=job.progress,
                )
            )
        if t_rel < duration:
            return None
        self.message = f"job {job.assignment.job_id} written"
        self._start_return(setpoint.position_m_enu)
        return job.recorder.finish(job.assignment.job_id, job.assignment.attempt)

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

    def status(self) -> VehicleStatus:
        """The vehicle's status message as of now (publish it when it changes)."""
        return VehicleStatus(
            vehicle_id=self.config.vehicle_id,
            kind=self.config.kind,
            state=self.state,
            board_id=self.config.board_id,
            job_id=self.job_id,
            message=self.message,
        )
