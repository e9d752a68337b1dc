"""The operator: commands and their replies, the show's snapshot and its events."""

from __future__ import annotations

from typing import Literal

from bus.messages.base import (
    ClientId,
    ErrorInfo,
    Id,
    JobIds,
    JobStateName,
    Priority,
    Request,
    State,
    Text,
    VehicleStateName,
)
from bus.messages.jobs import JobState


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
