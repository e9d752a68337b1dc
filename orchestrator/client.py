"""Blocking client calls to a show's orchestrator, for the command line (and scripts).

Each call opens a Zenoh client session to the show's router endpoints as the show's
``operator`` identity, asks, and closes it. It needs only the bus part of a show
(:class:`showfile.bus_view.ShowBus`: a loaded show, or the light view one-off commands read), so
importing this module loads neither pydantic nor numpy.
Errors: :class:`bus.rpc.NoReplyError` (no orchestrator answered), :class:`bus.rpc.RemoteError`
(it answered with an error), :class:`bus.session.SessionOpenError` (no router),
:class:`bus.codec.MessageError` (a ``ValueError``: a request the orchestrator would refuse to
decode, e.g. a ``client_id`` with a control character; nothing is sent).
"""

from __future__ import annotations

from typing import Any

import msgspec

from bus.codec import decode
from bus.keys import ShowKeys
from bus.messages import (
    CommandReply,
    OperatorCommand,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
)
from bus.rpc import query_one
from bus.session import open_session
from showfile.bus_view import ShowBus
from trust.settings import session_settings

DEFAULT_TIMEOUT_S = 5.0


def submit(
    show: ShowBus,
    *,
    text: str | None = None,
    strokes: dict[str, Any] | None = None,
    client_id: str = "cli",
    priority: int = 0,
    timeout_s: float = DEFAULT_TIMEOUT_S,
) -> SubmitReply:
    """Hand in a character (text or a strokes document) as the show's operator (on the plain
    ``submit`` key: never refused for quota); the reply carries the job id or error."""
    request = _checked(
        {"text": text, "strokes": strokes, "client_id": client_id, "priority": priority}
    )
    with open_session(session_settings(show, "operator"), role="client") as session:
        return query_one(
            session, ShowKeys(show.show_id).submit, request, SubmitReply, timeout_s=timeout_s
        )


def _checked(fields: dict[str, Any]) -> SubmitRequest:
    """The request as the orchestrator will decode it (field types, lengths, plain text);
    :class:`MessageError` naming the field, in one line, otherwise."""
    return decode(msgspec.json.encode(fields), SubmitRequest)


def command(
    show: ShowBus, operator_command: OperatorCommand, *, timeout_s: float = DEFAULT_TIMEOUT_S
) -> CommandReply:
    """Send an operator command; the reply says what happened."""
    with open_session(session_settings(show, "operator"), role="client") as session:
        return query_one(
            session,
            ShowKeys(show.show_id).command,
            operator_command,
            CommandReply,
            timeout_s=timeout_s,
        )


def snapshot(show: ShowBus, *, timeout_s: float = DEFAULT_TIMEOUT_S) -> ShowSnapshot:
    """The orchestrator's current view: every job (latest finished ones too) and vehicle."""
    with open_session(session_settings(show, "operator"), role="client") as session:
        return query_one(
            session, ShowKeys(show.show_id).snapshot, None, ShowSnapshot, timeout_s=timeout_s
        )
