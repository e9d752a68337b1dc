"""Vehicles: telemetry, status, the clock exchange, commands to an agent and what an agent
reports."""

from __future__ import annotations

from typing import Literal

from bus.messages.base import (
    Duration,
    ErrorInfo,
    Fraction,
    Id,
    Request,
    State,
    VehicleStateName,
)
from bus.messages.jobs import JobAssignment, JobMetrics


class Telemetry(State, frozen=True):
    """One vehicle at one instant; 20 Hz. World frame ENU, SI units."""

    vehicle_id: str
    t_s: float
    """Vehicle clock time in [s]."""
    state: VehicleStateName
    position_m_enu: tuple[float, float, float]
    velocity_mps_enu: tuple[float, float, float]
    reference_m_enu: tuple[float, float, float] | None = None
    pen_down: bool = False
    tracking_error_m: float = 0.0
    battery_fraction: float | None = None
    """0..1 when the backend knows it."""
    job_id: str | None = None
    progress: float = 0.0
    force_n: float | None = None
    """Measured normal contact force of the pen on its surface in [N], for kinds that sense it
    (``hexarotor-sponge``); None otherwise (v1 addition)."""
    force_reference_n: float | None = None
    """Wanted normal contact force in [N] now (the plan's, 0 in free flight), for kinds that
    control force; None otherwise (v1 addition)."""
    attitude_xyzw_enu: tuple[float, float, float, float] | None = None
    """The body's attitude: unit quaternion (x, y, z, w) turning body axes forward-left-up into
    world ENU; None: not known (at rest, an older agent) (v1 addition)."""
    writing_point_m_enu: tuple[float, float, float] | None = None
    """Where the writing point (brush tip, sponge, marker) is in [m], ENU; ``position_m_enu`` is
    the vehicle's reference point, which is the writing point itself for some kinds and the
    body's centre for others; None: not known (v1 addition)."""


class VehicleStatus(State, frozen=True):
    """A vehicle's state, published on change and at 1 Hz."""

    vehicle_id: str
    kind: str
    """Vehicle kind from the show file, e.g. ``quadrotor-brush``."""
    state: VehicleStateName
    board_id: str | None = None
    job_id: str | None = None
    message: str = ""
    incarnation: str | None = None
    """Random id of the agent's start (of each vehicle's, in a fleet host): a new one says the
    agent restarted, and has lost the job it had."""
    preflight: str = ""
    """Why the vehicle cannot take off now, in its autopilot's own words (a failing pre-arm
    check, e.g. ``Preflight Fail: horizontal velocity unstable``); empty: it can. The
    orchestrator gives it no job meanwhile, rather than have its arming refused and retried."""
    battery_fraction: float | None = None
    """Charge left in its battery over the rated capacity, 0..1, to the percent; None: unknown
    (v1 addition)."""
    battery_voltage_v: float | None = None
    """Battery terminal voltage under the present load in [V], to 0.1 V (v1 addition)."""
    battery_minutes_left: float | None = None
    """Minutes until its battery is empty, to 0.1 min: at its kind's cruise draw (simulated
    vehicles) or as its autopilot predicts (v1 addition)."""
    link_loss_fraction: float | None = None
    """Share of its autopilot's recent messages lost on the link, 0..1, to the percent; None:
    no autopilot link (simulated vehicles) or not enough messages yet (v1 addition)."""
    flight_s_today: float | None = None
    """How long in [s] it has been off the ground today (the agent's local day, since its agent
    started), to 10 s (v1 addition)."""
    clock_offset_ms: float | None = None
    """Its agent's wall clock minus the orchestrator's in [ms], to the millisecond, as measured
    on ``orchestrator/clock`` (``vehicle_agent/clock_sync.py``); None: not measured yet (v1
    addition)."""


class ClockReply(State, frozen=True):
    """Orchestrator -> an agent on ``orchestrator/clock``: its wall clock (Unix time [s]) when
    the query came and when it replied, NTP's receive and transmit timestamps (RFC 5905)."""

    receive_s: float
    transmit_s: float


class VehicleCommand(Request, frozen=True):
    """Orchestrator -> one agent."""

    command: Literal["assign", "cancel", "land", "estop", "clear_fault", "battery_swapped"]
    job: JobAssignment | None = None
    """Only with ``assign``."""
    job_id: Id | None = None
    """With ``cancel``: the job to stop."""


class AgentReport(Request, frozen=True):
    """Agent -> orchestrator: progress and the result of a job. Retried until acknowledged."""

    vehicle_id: Id
    job_id: Id
    event: Literal["holding", "started", "progress", "done", "failed", "ended"]
    """``holding``: the vehicle flies the job and has not begun writing it (a lease renewal);
    ``started``: writing begins; ``progress`` while writing; then ``done`` or ``failed``;
    ``ended`` (v1 addition): the job was stopped by something else (a cancel, a land, an
    emergency stop, a vehicle fault, its lease): what was written of it (``progress``, ``metrics``;
    ``error.code`` the reason), which changes nothing of the job."""
    planned_duration_s: Duration | None = None
    progress: Fraction = 0.0
    metrics: JobMetrics | None = None
    error: ErrorInfo | None = None
    retry_after_s: Duration | None = None
    """With ``failed``: the vehicle could not start the job but is healthy (its autopilot refused
    to take off); the job goes back to the queue and the vehicle takes no job for this long [s]."""
