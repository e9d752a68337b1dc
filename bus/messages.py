"""Every message on the bus: frozen, versioned msgspec structs, JSON on the wire.

Field names carry units and frames. Each struct has ``v`` (protocol version). Requests reject
unknown fields, so a typo in a client is an error rather than a silently ignored option; published
state accepts them, so newer publishers do not break older readers. docs/protocol.md documents all.
"""

from __future__ import annotations

from typing import Any, Literal, TypeVar

import msgspec

from bus.keys import PROTOCOL_VERSION

JobStateName = Literal[
    "submitted",
    "awaiting_approval",
    "queued",
    "assigned",
    "writing",
    "done",
    "failed",
    "cancelled",
    "rejected",
]
"""Life of a job; ``done``, ``failed``, ``cancelled`` and ``rejected`` are final."""

VehicleStateName = Literal[
    "idle",
    "taking_off",
    "writing",
    "returning",
    "landing",
    "landed",
    "fault",
    "lost",
]

MAX_PAYLOAD_BYTES = 1_000_000
"""Largest JSON payload any queryable accepts."""


class Request(msgspec.Struct, frozen=True, forbid_unknown_fields=True, kw_only=True):
    """Base of messages sent to a queryable."""

    v: int = PROTOCOL_VERSION


class State(msgspec.Struct, frozen=True, kw_only=True):
    """Base of published state and replies."""

    v: int = PROTOCOL_VERSION


class ErrorInfo(State, frozen=True):
    """What was wrong and where, for a human and for a program."""

    code: str
    """Stable machine-readable code, e.g. ``bad_json``, ``invalid_strokes``, ``unknown_job``."""
    message: str
    """One sentence a person understands."""
    field: str | None = None
    stroke_index: int | None = None
    point_index: int | None = None


# --- submissions --------------------------------------------------------------------------------


class SubmitRequest(Request, frozen=True):
    """A character handed in by the public (kiosk) or the operator (CLI)."""

    text: str | None = None
    """Typed text (one character or a short word); exactly one of ``text`` and ``strokes``."""
    strokes: dict[str, Any] | None = None
    """A strokes document as in docs/formats.md."""
    client_id: str = "anonymous"
    """Who handed it in (kiosk session, ``cli``); used for rate limits and status lookups."""
    priority: int = 0
    """Higher first; the operator may raise it."""


class SubmitReply(State, frozen=True):
    ok: bool
    job_id: str | None = None
    state: JobStateName | None = None
    queue_position: int | None = None
    """1 is next; None while awaiting approval."""
    eta_s: float | None = None
    """Seconds until the job should start writing, from planned durations."""
    error: ErrorInfo | None = None


# --- jobs ---------------------------------------------------------------------------------------


class JobMetrics(State, frozen=True):
    """How well a character was written (see the simulator's metrics.json)."""

    rmse_pen_down_m: float
    rmse_m: float
    max_error_m: float
    iou: float | None
    duration_s: float


class JobState(State, frozen=True):
    """A job as the orchestrator knows it; published on every change."""

    job_id: str
    state: JobStateName
    label: str
    """The typed text, or ``drawing (N strokes)``."""
    kind: Literal["text", "strokes"]
    client_id: str
    created_at_s: float
    """Unix time of the submission."""
    updated_at_s: float
    priority: int = 0
    vehicle_id: str | None = None
    queue_position: int | None = None
    eta_s: float | None = None
    planned_duration_s: float | None = None
    progress: float = 0.0
    """Fraction of the planned trajectory flown, 0..1."""
    attempts: int = 0
    """How many times it was assigned (a lost vehicle's job is assigned again)."""
    metrics: JobMetrics | None = None
    error: ErrorInfo | None = None
    strokes: dict[str, Any] | None = None
    """The strokes document of a drawn job, for previews: only in ``jobs/<id>`` publications
    and ``snapshot`` replies while the job awaits approval or is queued (never in ``fleet``)."""


class JobAssignment(State, frozen=True):
    """What a vehicle needs to write a job."""

    job_id: str
    text: str | None = None
    strokes: dict[str, Any] | None = None
    attempt: int = 1


# --- vehicles -----------------------------------------------------------------------------------


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


class VehicleStatus(State, frozen=True):
    """A vehicle's state, published on change and at 1 Hz."""

    vehicle_id: str
    kind: str
    """Vehicle kind from the show file, e.g. ``quadrotor-brush``."""
    state: VehicleStateName
    board_id: str | None = None
    job_id: str | None = None
    message: str = ""


class VehicleCommand(Request, frozen=True):
    """Orchestrator -> one agent."""

    command: Literal["assign", "cancel", "land", "estop"]
    job: JobAssignment | None = None
    """Only with ``assign``."""
    job_id: str | None = None
    """With ``cancel``: the job to stop."""


class AgentReport(Request, frozen=True):
    """Agent -> orchestrator: progress and the result of a job. Retried until acknowledged."""

    vehicle_id: str
    job_id: str
    event: Literal["started", "progress", "done", "failed"]
    planned_duration_s: float | None = None
    progress: float = 0.0
    metrics: JobMetrics | None = None
    error: ErrorInfo | None = None
    retry_after_s: float | None = None
    """With ``failed``: the vehicle could not start the job but is healthy (its autopilot refused
    to take off); the job goes back to the queue and the vehicle takes no job for this long [s]."""


# --- operator -----------------------------------------------------------------------------------


class OperatorCommand(Request, frozen=True):
    """Operator -> orchestrator."""

    command: Literal[
        "approve",
        "reject",
        "pause",
        "resume",
        "cancel",
        "land",
        "land_all",
        "estop",
        "prioritize",
    ]
    job_id: str | None = None
    vehicle_id: str | None = None
    priority: int | None = None
    reason: str = ""
    operator: str = "operator"


class CommandReply(State, frozen=True):
    ok: bool
    message: str = ""
    error: ErrorInfo | None = None


class VehicleSummary(State, frozen=True):
    """The orchestrator's view of one vehicle."""

    vehicle_id: str
    kind: str
    state: VehicleStateName
    alive: bool
    board_id: str | None = None
    job_id: str | None = None
    last_seen_s: float | None = None
    message: str = ""


class ShowSnapshot(State, frozen=True):
    """Everything a late joiner needs to draw the show at once."""

    show_id: str
    time_s: float
    """Orchestrator's Unix time."""
    queue_paused: bool
    jobs: list[JobState]
    vehicles: list[VehicleSummary]


class Event(State, frozen=True):
    """A line of the show's event log."""

    time_s: float
    level: Literal["info", "warning", "alert"]
    kind: str
    """e.g. ``vehicle_appeared``, ``vehicle_lost``, ``job_requeued``, ``operator``, ``limit``."""
    message: str
    vehicle_id: str | None = None
    job_id: str | None = None


# --- encoding -----------------------------------------------------------------------------------

M = TypeVar("M", bound=msgspec.Struct)

_encoder = msgspec.json.Encoder()


class MessageError(ValueError):
    """A payload that is not a valid message; ``info`` says what and where."""

    def __init__(self, info: ErrorInfo) -> None:
        self.info = info
        super().__init__(info.message)


def encode(message: msgspec.Struct) -> bytes:
    """JSON bytes of a message."""
    return _encoder.encode(message)


def decode(payload: bytes | bytearray | memoryview | str, message_type: type[M]) -> M:
    """Parse and validate a payload; raises :class:`MessageError` naming the problem."""
    raw = payload.encode() if isinstance(payload, str) else bytes(payload)
    if len(raw) > MAX_PAYLOAD_BYTES:
        raise MessageError(
            ErrorInfo(
                code="too_large",
                message=f"payload of {len(raw)} bytes exceeds {MAX_PAYLOAD_BYTES} bytes",
            )
        )
    try:
        return msgspec.json.decode(raw, type=message_type)
    except msgspec.ValidationError as exc:
        text = str(exc)
        field = text.rsplit("at `", 1)[1].rstrip("`") if "at `" in text else None
        raise MessageError(ErrorInfo(code="invalid", message=text, field=field)) from None
    except msgspec.DecodeError as exc:
        raise MessageError(ErrorInfo(code="bad_json", message=f"not valid JSON: {exc}")) from None
