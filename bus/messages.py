"""Every message on the bus: frozen, versioned msgspec structs, JSON on the wire.

Field names carry units and frames. Each struct has ``v`` (protocol version). Requests reject
unknown fields, so a typo in a client is an error rather than a silently ignored option; published
state accepts them, so newer publishers do not break older readers. docs/protocol.md documents all;
``bus.codec`` turns them into JSON bytes and back.
"""

from __future__ import annotations

import math
from typing import Annotated, Any, Literal

import msgspec

from bus.keys import PROTOCOL_VERSION
from bus.public_text import MAX_CLIENT_ID_CHARS, MAX_LABEL_CHARS, text_problem

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
    "battery_swap",
]
"""A vehicle's state as it reports it; ``lost`` and ``battery_swap`` only as the orchestrator
sees it (``battery_swap``: on the ground, waiting for the crew to change its battery)."""
AIRBORNE_STATES: frozenset[VehicleStateName] = frozenset(
    {"taking_off", "writing", "returning", "landing"}
)
"""Vehicle states in which it is in the air (or moving, for a ground vehicle)."""

MAX_ID_CHARS = 128
"""Longest job or vehicle id a request may carry."""
MAX_TEXT_CHARS = 1000
"""Longest free text (``text``, ``client_id``, ``reason``, ``operator``) a request may carry;
services may allow less (a typed text is at most 64 characters, a client id at most 100)."""
MAX_PRIORITY = 1000
"""Largest priority magnitude a request may carry (submissions allow -10..10)."""
MAX_DURATION_S = 1e6
"""Longest duration a request may state, [s]."""
MAX_BULK_JOBS = 1000
"""Most jobs one operator command may name (``job_ids``)."""
MAX_SNAPSHOT_ALERTS = 50
"""Most open alerts a :class:`ShowSnapshot` carries (the newest)."""

Id = Annotated[str, msgspec.Meta(min_length=1, max_length=MAX_ID_CHARS)]
"""A job or vehicle id in a request."""
Text = Annotated[str, msgspec.Meta(max_length=MAX_TEXT_CHARS)]
"""Free text in a request."""
ClientId = Annotated[str, msgspec.Meta(max_length=MAX_CLIENT_ID_CHARS)]
"""Who hands a submission in (plain text, :mod:`bus.public_text`)."""
Priority = Annotated[int, msgspec.Meta(ge=-MAX_PRIORITY, le=MAX_PRIORITY)]
"""A job priority in a request; higher first."""
Version = Annotated[int, msgspec.Meta(ge=0, le=1_000_000)]
IdempotencyKey = Annotated[str, msgspec.Meta(min_length=1, max_length=64)]
"""A client's name for one submission; the same key answers with the same job."""
"""A protocol version number."""
Fraction = Annotated[float, msgspec.Meta(ge=0.0, le=1.0)]
"""A fraction 0..1."""
Duration = Annotated[float, msgspec.Meta(ge=0.0, le=MAX_DURATION_S)]
"""A duration in a request, [s]."""
JobIds = Annotated[list[Id], msgspec.Meta(min_length=1, max_length=MAX_BULK_JOBS)]
"""Several job ids in a request (1..``MAX_BULK_JOBS``)."""


class Request(msgspec.Struct, frozen=True, forbid_unknown_fields=True, kw_only=True):
    """Base of messages sent to a queryable."""

    v: Version = PROTOCOL_VERSION


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
    reason: str | None = None
    """``rejected`` / ``cancelled``: the operator's own words for the visitor who handed the job
    in (plain text; a kiosk shows it as text, cut to a line); None when none was given (v1
    addition)."""


# --- submissions --------------------------------------------------------------------------------


class SubmitRequest(Request, frozen=True):
    """A character handed in by the public (kiosk) or the operator (CLI)."""

    text: Text | None = None
    """Typed text (one character or a short word); exactly one of ``text`` and ``strokes``."""
    strokes: dict[str, Any] | None = None
    """A strokes document as in docs/formats.md."""
    client_id: ClientId = "anonymous"
    """Who handed it in (kiosk session, ``cli``); used for rate limits and status lookups."""
    priority: Priority = 0
    """Higher first; the operator may raise it."""
    idempotency_key: IdempotencyKey | None = None
    """Optional key chosen by the client (1-64 chars): a request repeating a key already accepted
    from the same ``client_id`` gets that job's reply instead of a new job (safe retries)."""
    phrase: bool = False
    """``text`` is a phrase: one job per character, written together on adjacent boards in
    reading order, at most as many characters as the show has boards in a row; the reply names
    the first character's job, whose id is the phrase's (v1 addition)."""

    def __post_init__(self) -> None:
        """Refuse what is not plain text (:mod:`bus.public_text`): at decode, an ``invalid``
        naming the field, as msgspec's own errors do."""
        checked = [("client_id", self.client_id, True), ("text", self.text, False)]
        checked += [(f"strokes.{key}", (self.strokes or {}).get(key), True) for key in _NAMED]
        for field, value, name in checked:
            if not isinstance(value, str):
                continue  # absent, or not a string: the planner's parsing refuses it
            why = (
                f"is longer than {MAX_LABEL_CHARS} characters"
                if field.startswith("strokes.") and len(value) > MAX_LABEL_CHARS
                else text_problem(value, name=name)
            )
            if why is not None:
                raise ValueError(f"{field} {why}: public text is plain text - at `$.{field}`")


_NAMED = ("label", "device")
"""Free text of a strokes document, checked as names."""


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


MAX_INK_PX = 256
"""Most pixels along either side of a :class:`WrittenInk` raster."""
MAX_INK_BYTES = MAX_INK_PX * MAX_INK_PX // 8
"""Most bytes of a :class:`WrittenInk` raster's packed bits (8 kB; base64 on the wire)."""
InkPixels = Annotated[int, msgspec.Meta(ge=1, le=MAX_INK_PX)]


class WrittenInk(State, frozen=True, kw_only=True):
    """The ink a vehicle left on its board for one job: a 1-bit raster for pictures, not scores.

    Pixel (row, column) covers board x from ``x_min + column * w`` and board y from
    ``y_max - (row + 1) * h`` (``w``, ``h``: extent over width/height in pixels): row 0 is the top
    (largest board y). ``bits`` holds the rows top first, each left to right, 8 pixels a byte,
    the first pixel in the most significant bit, no padding between rows (the last byte is
    padded with zeros); 1 is ink. On the wire ``bits`` is standard base64 (JSON string).
    """

    format: Literal["bitmap1"] = "bitmap1"
    """Layout of ``bits``; a new layout gets a new name."""
    width_px: InkPixels
    """Pixels per row (along board x)."""
    height_px: InkPixels
    """Rows (along board y)."""
    extent_m_board: tuple[float, float, float, float]
    """``(x_min, y_min, x_max, y_max)`` of the raster's outer pixel edges in the board frame
    (origin at the writing area's centre, x right, y up as the visitor sees the board), [m]."""
    bits: Annotated[bytes, msgspec.Meta(max_length=MAX_INK_BYTES)]
    """The packed pixels (see above): exactly ``ceil(width_px * height_px / 8)`` bytes."""

    def __post_init__(self) -> None:
        need = -(-self.width_px * self.height_px // 8)
        if len(self.bits) != need:
            raise ValueError(
                f"bits has {len(self.bits)} bytes; {self.width_px}x{self.height_px} pixels need "
                f"{need}"
            )
        x_min, y_min, x_max, y_max = self.extent_m_board
        if not all(math.isfinite(v) for v in self.extent_m_board) or not (
            x_max > x_min and y_max > y_min
        ):
            raise ValueError(f"extent_m_board {self.extent_m_board} is not a finite box")


class JobMetrics(State, frozen=True):
    """How well a character was written (see the simulator's metrics.json)."""

    rmse_pen_down_m: float | None
    """RMSE in [m] of the writing point while the pen was meant to be down; None: the pen never
    came down, so nothing was measured (null on the wire, v1 addition: was always a number)."""
    rmse_m: float
    max_error_m: float
    iou: float | None
    """Ink IoU of what was written against the whole target character (0: nothing of it
    written); None: the backend does not know its brush."""
    duration_s: float
    written: WrittenInk | None = None
    """The ink left on the board, when the vehicle knows its brush (sent with the ``done``
    report and on ``jobs/<id>``; the orchestrator keeps it out of ``fleet``)."""
    extra: dict[str, float] = {}
    """The kind's own figures, names with units: the wall hexarotor's ``rmse_ee_m``,
    ``rmse_base_m``, ``force_rmse_n``, ``width_rmse_m``; empty for kinds without any."""
    flown_fraction: float = 1.0
    """Fraction 0..1 of the plan's duration flown; below 1 the job was written in part (an abort):
    the errors cover what was flown, the IoU the whole target (v1 addition)."""


class PhrasePlace(State, frozen=True):
    """A job's place in a phrase written together (v1 addition)."""

    phrase_id: str
    """The phrase's id: its first character's job id."""
    index: int
    """Its character's place in reading order, 0 first (its board's place in the row too)."""
    size: int
    """Characters in the phrase."""


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
    phrase: PhrasePlace | None = None
    """Its place in a phrase written together; None: a job of its own (v1 addition)."""


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
        "release",
        "release_all",
        "clear_fault",
        "fresh_sheet",
        "battery_swapped",
    ]
    job_id: Id | None = None
    vehicle_id: Id | None = None
    board_id: Id | None = None
    """``fresh_sheet``: the board whose sheet was replaced (v1 addition). ``battery_swapped``
    names its vehicle in ``vehicle_id`` (v1 addition)."""
    priority: Priority | None = None
    reason: Text = ""
    operator: Text = "operator"
    job_ids: JobIds | None = None
    """``reject`` / ``cancel`` of these jobs at once, instead of ``job_id`` (v1 addition)."""
    client_id: ClientId | None = None
    """``reject`` / ``cancel`` of every waiting job this client handed in (the ``client_id`` it
    declared, or the certificate it submitted with), instead of ``job_id`` (v1 addition)."""


class CommandReply(State, frozen=True):
    ok: bool
    message: str = ""
    error: ErrorInfo | None = None


class SkippedJob(State, frozen=True):
    """A job a bulk ``reject`` / ``cancel`` left as it was, and why."""

    job_id: str
    state: JobStateName | None
    """Its state (None: no such job)."""
    reason: str
    """One line, e.g. ``writing on uav1``."""


class OperatorReply(CommandReply, frozen=True):
    """The reply of the ``command`` queryable: a :class:`CommandReply` which, for a bulk
    ``reject`` / ``cancel`` (``job_ids`` or ``client_id``), names what it did (v1 addition)."""

    job_ids: list[str] = []
    """The jobs rejected or cancelled, in submission order."""
    skipped: list[SkippedJob] = []
    """Named jobs (``job_ids``), or unfinished jobs of the client (``client_id``), left as they
    were: not waiting, being written, or unknown."""


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
    held: bool = False
    """Landed or stopped by the operator: it takes no job until a ``release`` (v1 addition)."""
    paused: bool = False
    """Paused by the operator (and not held): it finishes its job, then takes no new one until
    ``resume`` (v1 addition)."""
    battery_fraction: float | None = None
    """Its latest status's ``battery_fraction`` (v1 addition)."""
    battery_minutes_left: float | None = None
    """Its latest status's ``battery_minutes_left`` (v1 addition)."""
    preflight: str = ""
    """Its latest status's ``preflight``: why it may not take off now (v1 addition)."""
    link_loss_fraction: float | None = None
    """Its latest status's ``link_loss_fraction`` (v1 addition)."""
    flight_s_today: float | None = None
    """Its latest status's ``flight_s_today`` (v1 addition)."""


class ShowSnapshot(State, frozen=True):
    """Everything a late joiner needs to draw the show at once."""

    show_id: str
    time_s: float
    """Orchestrator's Unix time."""
    queue_paused: bool
    jobs: list[JobState]
    vehicles: list[VehicleSummary]
    events: list[Event] = []
    """The latest lines of the event log, oldest first, read from the orchestrator's database so
    a restart keeps them (``snapshot`` replies only; v1 addition)."""
    alerts: list[Event] = []
    """The open alerts: those whose cause lasts (a vehicle held, lost or in fault, a board
    half-written; docs/protocol.md), oldest first, the newest ``MAX_SNAPSHOT_ALERTS`` at most,
    however long ago they were raised (v1 addition)."""
    dirty_boards: list[str] = []
    """Boards left half-written (a job requeued after writing started): no job is assigned there
    until the operator confirms a fresh sheet (``fresh_sheet``; v1 addition)."""
    job_counts: dict[str, int] = {}
    """How many jobs of the show are in each state, all of them: ``jobs`` may leave out older
    finished ones (states with no job are absent; v1 addition)."""


class Event(State, frozen=True):
    """A line of the show's event log."""

    time_s: float
    level: Literal["info", "warning", "alert"]
    kind: str
    """e.g. ``vehicle_appeared``, ``vehicle_lost``, ``job_requeued``, ``operator``, ``limit``."""
    message: str
    vehicle_id: str | None = None
    job_id: str | None = None
