"""Submissions: a character handed in (kiosk or CLI) and the orchestrator's answer."""

from __future__ import annotations

from typing import Any

from bus.messages.base import (
    ClientId,
    ErrorInfo,
    IdempotencyKey,
    JobStateName,
    Priority,
    Request,
    State,
    Text,
)
from bus.public_text import MAX_LABEL_CHARS, text_problem


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
