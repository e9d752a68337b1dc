"""What goes into and out of the job runner: configuration, planned jobs, per-tick actions."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from numpy.typing import NDArray

from bus.messages import (
    AgentReport,
    CommandReply,
    ErrorInfo,
    JobAssignment,
    JobMetrics,
    Telemetry,
    VehicleStateName,
)
from planner.samples import TrajectorySamples
from vehicle_agent.backends.base import Setpoint, Vec3, VehicleSnapshot
from vehicle_agent.preflight import PreflightLimits
from vehicle_agent.safety.limits import SafetyLimits
from vehicle_agent.trace import JobTrace
from vehicles.verdict import WritingBounds, writing_verdict

ACTIVE_PHASES = ("preflight", "climb", "wait_plan", "transit", "settle", "write")
"""Phases in which a job is running (an interruption lifts the brush and abandons it)."""

BackendCommand = tuple[str, Vec3 | None]
"""``("takeoff", hover)``, ``("land", None)`` or ``("estop", None)``."""


@dataclass(frozen=True)
class RunnerConfig:
    """Everything the runner needs to know about its vehicle, from the show file."""

    vehicle_id: str
    """Vehicle id from the show file."""
    kind: str
    """Vehicle kind, e.g. ``quadrotor-brush``."""
    board_id: str | None
    """The board this vehicle writes on."""
    home_m_enu: Vec3
    """Where the vehicle rests on the ground in [m], ENU."""
    cruise_z_m: float
    """Height in [m] (world z) of pen-up flight: board surface + write height + clearance."""
    v_max_mps: float
    """Speed limit in [m/s] for transit moves."""
    a_max_mps2: float
    """Acceleration limit in [m/s^2] for transit moves (the smallest per-axis limit)."""
    airborne: bool = True
    """It takes off and lands (``vehicles.kind.JobPhases.airborne``); False: a ground vehicle,
    whose take-off and landing end at once and whose pen-up height is the floor's."""
    route: Literal["straight", "sideways_first"] = "straight"
    """Shape of the pen-up moves (``vehicles.kind.JobPhases.route``)."""
    transit_wait_m: float | None = None
    """The pen-up reference waits while the vehicle is this far behind in [m]
    (``vehicles.kind.JobPhases.transit_wait_m``); None: it never waits."""
    telemetry_period_s: float = 0.05
    """Agent time in [s] between telemetry messages (20 Hz at time scale 1)."""
    progress_period_s: float = 1.0
    """Agent time in [s] between progress reports while writing."""
    takeoff_retry_s: float = 5.0
    """After its take-off was refused (pre-arm checks) the vehicle takes no job for this long in
    [s] (agent time)..."""
    takeoff_retry_max_s: float = 60.0
    """...doubled at each refusal in a row, up to this many [s]."""
    safety: SafetyLimits = field(default_factory=SafetyLimits)
    """Deviation bound, geofence, writing bounds, settling and the abort policy."""
    preflight: PreflightLimits | None = None
    """The bounds of the agent's preflight before each job (None: only the autopilot's own
    pre-arm checks, e.g. unit tests of other things)."""

    @property
    def hover_home_m_enu(self) -> Vec3:
        """The hover point above home in [m], at cruise height (a ground vehicle: home)."""
        if not self.airborne:
            return self.home_m_enu
        return (self.home_m_enu[0], self.home_m_enu[1], self.cruise_z_m)

    def legs(self, start_m_enu: Vec3, end_m_enu: Vec3) -> tuple[Vec3, ...]:
        """The ends of the straight legs of a pen-up move along ``route`` (the last is
        ``end_m_enu``): ``sideways_first`` goes along world y on the starting level, then along
        world x."""
        if self.route == "straight":
            return (end_m_enu,)
        corner = (start_m_enu[0], end_m_enu[1], start_m_enu[2])
        if math.dist(corner, start_m_enu) < 1e-6 or math.dist(corner, end_m_enu) < 1e-6:
            return (end_m_enu,)
        return (corner, end_m_enu)


@dataclass(frozen=True)
class PreparedJob:
    """A job laid out on the board and planned, ready to fly."""

    job_id: str
    """The orchestrator's job id."""
    samples: TrajectorySamples
    """The planned reference (where the brush should be), at rest above the first stroke at 0."""
    command_samples: TrajectorySamples | None = None
    """What to send the vehicle, same times (e.g. the body reference that puts the brush tip on
    ``samples``); None: ``samples`` itself."""
    context: object = None
    """Whatever the metrics of the flown job need later (the laid-out glyph, the board...)."""
    force_n: NDArray[np.float64] | None = None
    """(N,) wanted normal contact force in [N] at the times of ``samples`` (kinds that control
    force), None otherwise."""
    label: str = ""
    """What the job writes, for people: its typed text, or ``drawing (N strokes)`` (as
    ``bus.messages.JobState.label``); empty: not known (the job's id stands for it)."""


@dataclass(frozen=True)
class RunnerEvent:
    """A line for the show's event log about this vehicle (published on its ``events`` key)."""

    level: Literal["info", "warning", "alert"]
    """How loud: ``alert`` for aborts and faults."""
    kind: str
    """e.g. ``deviation``, ``geofence``, ``not_settled``, ``vehicle_fault``, ``vehicle_mode``,
    ``preflight``."""
    message: str
    """One sentence for a person."""
    job_id: str | None = None
    """The job concerned, if any."""


@dataclass(frozen=True)
class AbortedJob:
    """A job broken off after its writing began: what was flown of it, to measure against the
    whole plan and keep as a finished job's files are kept (``vehicle_agent/jobs.py``)."""

    trace: JobTrace
    """What was flown until it stopped (``flown.abort_reason``: why)."""
    report: AgentReport | None
    """Its ``failed`` result (a safety abort: final), to send with its metrics once measured;
    None: an interruption (the orchestrator asked for it, or takes the job back itself,
    ``vehicle_agent/job_runner.py``): no result decides the job, only an ``ended`` report says
    what was written (``vehicle_agent/end_reasons.py``)."""


@dataclass(frozen=True)
class TickActions:
    """What the service must do in this control period, in this order."""

    backend_command: BackendCommand | None = None
    """A mode change to send to the backend before ticking it."""
    setpoint: Setpoint | None = None
    """The reference for ``backend.tick`` (None: the backend's mode is in charge)."""
    plan_request: JobAssignment | None = None
    """A job to lay out and plan (off the control loop); answer with ``plan_ready/failed``."""
    reports: tuple[AgentReport, ...] = ()
    """Reports for the orchestrator, in order (started/failed must be retried until acked)."""
    telemetry: Telemetry | None = None
    """A telemetry message to publish now."""
    finished: JobTrace | None = None
    """A job just flown to its end: compute its metrics and report it (:func:`result_report`)."""
    aborted: AbortedJob | None = None
    """A job just broken off after its writing began: measure it, keep its files, and send its
    report (if any) with its metrics."""
    events: tuple[RunnerEvent, ...] = ()
    """Events for the show's log (aborts, faults, autopilot mode changes), oldest first."""


def done_report(vehicle_id: str, trace: JobTrace, metrics: JobMetrics | None) -> AgentReport:
    """The ``done`` report of a flown job with its metrics."""
    return AgentReport(
        vehicle_id=vehicle_id,
        job_id=trace.job_id,
        event="done",
        progress=1.0,
        planned_duration_s=trace.duration_s,
        metrics=metrics,
    )


def result_report(
    vehicle_id: str, trace: JobTrace, metrics: JobMetrics | None, bounds: WritingBounds
) -> AgentReport:
    """``done`` when the written job met ``bounds``; ``failed`` with code ``writing_bounds`` (the
    metrics attached) when it did not, or ``unmeasured`` when it could not be measured."""
    if metrics is None:
        error = ErrorInfo(code="unmeasured", message="the written job could not be measured")
    else:
        why = writing_verdict(
            metrics.rmse_pen_down_m, metrics.iou, bounds, flown_fraction=metrics.flown_fraction
        )
        if why is None:
            return done_report(vehicle_id, trace, metrics)
        error = ErrorInfo(code="writing_bounds", message=f"written out of bounds: {why}")
    return AgentReport(
        vehicle_id=vehicle_id,
        job_id=trace.job_id,
        event="failed",
        progress=1.0,
        planned_duration_s=trace.duration_s,
        metrics=metrics,
        error=error,
    )


def _wanted_force_n(snap: VehicleSnapshot, setpoint: Setpoint | None) -> float | None:
    """The contact force wanted now in [N] for a vehicle that senses force (0 off contact)."""
    if snap.force_n is None:
        return None
    wanted = None if setpoint is None else setpoint.force_n
    return 0.0 if wanted is None else wanted


def telemetry_message(
    vehicle_id: str,
    state: VehicleStateName,
    snap: VehicleSnapshot,
    setpoint: Setpoint | None,
    now_s: float,
    *,
    job_id: str | None,
    progress: float,
) -> Telemetry:
    """Telemetry of the vehicle in ``snap`` following ``setpoint`` (pen from the backend when it
    knows the brush, else from the reference; attitude and writing point when it knows them)."""
    ref = None if setpoint is None else setpoint.position_m_enu
    pen = (
        snap.pen_contact
        if snap.pen_contact is not None
        else (setpoint is not None and setpoint.pen_down)
    )
    return Telemetry(
        vehicle_id=vehicle_id,
        t_s=now_s,
        state=state,
        position_m_enu=snap.position_m_enu,
        velocity_mps_enu=snap.velocity_mps_enu,
        reference_m_enu=ref,
        pen_down=bool(pen),
        tracking_error_m=0.0 if ref is None else math.dist(ref, snap.position_m_enu),
        battery_fraction=snap.battery_fraction,
        job_id=job_id,
        progress=progress,
        force_n=snap.force_n,
        force_reference_n=_wanted_force_n(snap, setpoint),
        attitude_xyzw_enu=snap.attitude_xyzw_enu,
        writing_point_m_enu=snap.pen_tip_m_enu,
    )


def takeoff_refused_report(
    vehicle_id: str, job_id: str, reason: str, retry_after_s: float
) -> AgentReport:
    """The job handed back because the vehicle refused to take off (it stays available)."""
    return AgentReport(
        vehicle_id=vehicle_id,
        job_id=job_id,
        event="failed",
        error=ErrorInfo(code="takeoff_refused", message=reason),
        retry_after_s=retry_after_s,
    )


def refuse(code: str, message: str, *, field: str | None = None) -> CommandReply:
    return CommandReply(
        ok=False, message=message, error=ErrorInfo(code=code, message=message, field=field)
    )
