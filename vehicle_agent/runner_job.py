"""One job inside the job runner (pure): its plan, its flown trace, its reports."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from bus.messages import AgentReport, ErrorInfo, JobAssignment
from vehicle_agent.backends.base import Setpoint, VehicleSnapshot
from vehicle_agent.reference_track import ReferenceTrack
from vehicle_agent.runner_io import PreparedJob
from vehicle_agent.trace import JobTrace, TraceRecorder

ReportEvent = Literal["started", "progress", "done", "failed"]


@dataclass
class RunningJob:
    """A job from its assignment until the vehicle is back on the ground (or it is dropped)."""

    assignment: JobAssignment
    """What the orchestrator asked for."""
    prepared: PreparedJob | None = None
    """The plan, once ready and inside the fence."""
    plan_requested: bool = False
    """The plan was asked for (once)."""
    started_s: float | None = None
    """Agent time in [s] writing began (the brush may touch from here on)."""
    recorder: TraceRecorder = field(default_factory=TraceRecorder)
    """What was flown while writing."""
    progress: float = 0.0
    """Fraction 0..1 of the plan written."""
    next_progress_s: float = 0.0
    """Agent time in [s] of the next progress report."""
    planned_now: Setpoint | None = None
    """The plan's sample at this tick: set by :meth:`setpoint`, recorded by :meth:`record`."""
    approaches: int = 0
    """Approaches to the start of the plan flown so far (settling)."""
    _tracks: tuple[ReferenceTrack, ReferenceTrack | None] | None = field(
        default=None, init=False, repr=False
    )
    """The plan's reference and the commanded one (None: the same), made at the first tick."""

    @property
    def job_id(self) -> str:
        return self.assignment.job_id

    @property
    def started(self) -> bool:
        """Writing has begun: the board may carry ink of this job."""
        return self.started_s is not None

    @property
    def written(self) -> bool:
        """Written to its end: its result is the finished job's (``TickActions.finished``)."""
        return self.progress >= 1.0

    def setpoint(self, now_s: float) -> Setpoint:
        """What to command at agent time ``now_s`` while writing (the body reference when the
        plan has one; the pen state is the plan's)."""
        assert self.prepared is not None and self.started_s is not None
        if self._tracks is None:
            prepared = self.prepared
            commands = prepared.command_samples
            self._tracks = (
                ReferenceTrack(prepared.samples, prepared.force_n),
                None if commands is None else ReferenceTrack(commands),
            )
        planned_track, command_track = self._tracks
        t_rel_s = now_s - self.started_s
        self.planned_now = planned = planned_track.at(t_rel_s)
        if command_track is None:
            return planned
        position, velocity, acceleration = command_track.motion_at(t_rel_s)
        return Setpoint(position, velocity, acceleration, planned.pen_down, planned.force_n)

    def record(self, snap: VehicleSnapshot, now_s: float) -> bool:
        """Record this tick; True once the plan is written to its end."""
        assert self.prepared is not None and self.started_s is not None
        assert self.planned_now is not None
        t_rel = now_s - self.started_s
        duration = self.prepared.samples.duration_s
        self.recorder.add(t_rel, snap, self.planned_now)
        self.progress = min(t_rel / duration, 1.0) if duration > 0 else 1.0
        return t_rel >= duration

    def finish(self) -> JobTrace:
        """The flown trace of the whole job."""
        return self.recorder.finish(self.job_id, self.assignment.attempt)

    def broken_off(self, reason: str) -> JobTrace | None:
        """What was flown of the job, stopped before its end for ``reason`` (e.g.
        ``deviation``, ``cancelled``: ``FlownWriting.abort_reason``); None when nothing was
        (writing had not begun) or the job was written to its end."""
        if self.written or not len(self.recorder):
            return None
        return self.recorder.finish(self.job_id, self.assignment.attempt, abort_reason=reason)

    def report(
        self,
        vehicle_id: str,
        event: ReportEvent,
        *,
        error: ErrorInfo | None = None,
        retry_after_s: float | None = None,
        planned_duration_s: float | None = None,
    ) -> AgentReport:
        """A report about this job, with its progress."""
        return AgentReport(
            vehicle_id=vehicle_id,
            job_id=self.job_id,
            event=event,
            progress=self.progress,
            error=error,
            retry_after_s=retry_after_s,
            planned_duration_s=planned_duration_s,
        )

    def aborted(self, vehicle_id: str, code: str, message: str, backoff_s: float) -> AgentReport:
        """``failed`` with ``code``: before writing began the job goes back to the queue (the
        vehicle is healthy enough to say so, the board is clean: ``retry_after_s`` set); once
        the brush may have touched, it is final."""
        retry = None if self.started else backoff_s
        error = ErrorInfo(code=code, message=message)
        return self.report(vehicle_id, "failed", error=error, retry_after_s=retry)
