"""Every message on the bus: frozen, versioned msgspec structs, JSON on the wire.

Field names carry units and frames. Each struct has ``v`` (protocol version). Requests reject
unknown fields, so a typo in a client is an error rather than a silently ignored option; published
state accepts them, so newer publishers do not break older readers. docs/protocol.md documents all;
``bus.codec`` turns them into JSON bytes and back.

One module per part of the protocol: ``base`` (state names, request bounds, the bases and
:class:`ErrorInfo`), ``submissions``, ``jobs``, ``vehicles`` and ``operator``; every message is
imported from here.
"""

from __future__ import annotations

from bus.messages.base import (
    AIRBORNE_STATES,
    MAX_BULK_JOBS,
    MAX_DURATION_S,
    MAX_ID_CHARS,
    MAX_PRIORITY,
    MAX_SNAPSHOT_ALERTS,
    MAX_TEXT_CHARS,
    ClientId,
    Duration,
    ErrorInfo,
    Fraction,
    Id,
    IdempotencyKey,
    JobIds,
    JobStateName,
    Priority,
    Request,
    State,
    Text,
    VehicleStateName,
    Version,
)
from bus.messages.jobs import (
    MAX_INK_BYTES,
    MAX_INK_PX,
    InkPixels,
    JobAssignment,
    JobMetrics,
    JobState,
    PhrasePlace,
    WrittenInk,
)
from bus.messages.operator import (
    CommandReply,
    Event,
    OperatorCommand,
    OperatorReply,
    ShowSnapshot,
    SkippedJob,
    VehicleSummary,
)
from bus.messages.submissions import (
    SubmitReply,
    SubmitRequest,
)
from bus.messages.vehicles import (
    AgentReport,
    ClockReply,
    Telemetry,
    VehicleCommand,
    VehicleStatus,
)

__all__ = [
    "AIRBORNE_STATES",
    "MAX_BULK_JOBS",
    "MAX_DURATION_S",
    "MAX_ID_CHARS",
    "MAX_INK_BYTES",
    "MAX_INK_PX",
    "MAX_PRIORITY",
    "MAX_SNAPSHOT_ALERTS",
    "MAX_TEXT_CHARS",
    "AgentReport",
    "ClientId",
    "ClockReply",
    "CommandReply",
    "Duration",
    "ErrorInfo",
    "Event",
    "Fraction",
    "Id",
    "IdempotencyKey",
    "InkPixels",
    "JobAssignment",
    "JobIds",
    "JobMetrics",
    "JobState",
    "JobStateName",
    "OperatorCommand",
    "OperatorReply",
    "PhrasePlace",
    "Priority",
    "Request",
    "ShowSnapshot",
    "SkippedJob",
    "State",
    "SubmitReply",
    "SubmitRequest",
    "Telemetry",
    "Text",
    "VehicleCommand",
    "VehicleStateName",
    "VehicleStatus",
    "VehicleSummary",
    "Version",
    "WrittenInk",
]
