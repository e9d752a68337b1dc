"""The bus messages' building blocks: names of states, bounds of what a request may carry,
the bases of requests and of published state, and the error every reply may carry."""

from __future__ import annotations

from typing import Annotated, Literal

import msgspec

from bus.keys import PROTOCOL_VERSION
from bus.public_text import MAX_CLIENT_ID_CHARS

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
"""A protocol version number."""
IdempotencyKey = Annotated[str, msgspec.Meta(min_length=1, max_length=64)]
"""A client's name for one submission; the same key answers with the same job."""
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
