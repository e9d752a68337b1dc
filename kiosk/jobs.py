"""The kiosk's own tickets: who may read them (a token each) and how they look to the page.

A ticket is made before the submission is sent. It carries the submission's idempotency key, so
the kiosk can send it again until the orchestrator answers; the orchestrator's job id is bound to
it when the answer comes (at once, or late after a hang). Pages follow the ticket, not the job.

Pure bookkeeping: no I/O. The bus link feeds :class:`JobState` messages in; the app reads views out.
"""

from __future__ import annotations

import hmac
import secrets
from collections import OrderedDict
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import msgspec

from bus.messages import JobMetrics, JobState
from kiosk import wording
from kiosk.ink_view import written_view
from kiosk.phrase_view import phrase_view

FINAL_STATES = frozenset({"done", "failed", "cancelled", "rejected"})
"""Job states after which nothing changes."""
CODE_ALPHABET = "ABCDEFGHJKMNPQRSTUVWXYZ23456789"
"""Letters and digits of short codes, without look-alikes (0/O, 1/I/L)."""
CODE_LENGTH = 8
"""Characters of a short code (31**8: about 40 bits; lookups are rate limited)."""


def new_code() -> str:
    """A short code to follow a ticket from another device (``/t/<code>``)."""
    return "".join(secrets.choice(CODE_ALPHABET) for _ in range(CODE_LENGTH))


def normal_code(text: str) -> str:
    """A typed code as stored: upper case, without spaces and dashes."""
    return "".join(ch for ch in text.upper() if ch not in " -")[: CODE_LENGTH + 4]


@dataclass
class KioskJob:
    """A submission handed in through this kiosk (its ticket)."""

    ticket: str
    """This kiosk's id of the submission (in the page's URLs)."""
    token: str
    """Secret returned to the submitting page; required to read the ticket."""
    session_id: str
    """Cookie session of the submitting browser."""
    label: str
    """The typed text or ``drawing (N strokes)``."""
    preview: dict[str, Any] | None
    """The planned path shown before submitting (the picture of the result)."""
    key: str
    """Idempotency key sent with every try of this submission."""
    code: str = ""
    """Short code that opens this ticket on another device (like the token, it grants reading)."""
    job_id: str | None = None
    """Orchestrator's job id, once it acknowledged the submission."""
    refusal: str | None = None
    """What to tell the visitor when a late answer refused the submission."""
    refusal_code: str | None = None
    """The code of that refusal (the page words it)."""
    phrase_size: int = 0
    """Characters of a phrase written together (one job each, ``kiosk/phrase_view.py``); 0:
    one job."""

    @property
    def pending(self) -> bool:
        """Sent, but not answered yet."""
        return self.job_id is None and self.refusal is None


def metrics_view(m: JobMetrics | None) -> dict[str, Any] | None:
    """The public part of a job's result: errors (``rmse_pen_down_m`` None: not measured, the
    pen never came down), overlap, time, how much of the plan was flown and the ink picture."""
    if m is None:
        return None
    return {
        "rmse_pen_down_m": m.rmse_pen_down_m,
        "max_error_m": m.max_error_m,
        "iou": m.iou,
        "duration_s": m.duration_s,
        "flown_fraction": m.flown_fraction,
        "written": written_view(m.written),
    }


def job_view(
    state: JobState, places: Mapping[str, int] | None = None, *, show_paused: bool = False
) -> dict[str, Any]:
    """What the page is told about a job: public fields and a sentence to show (English; the
    page words the fields in the visitor's language).

    ``places``: vehicle id -> position of its board from the left (1 first); ``show_paused``:
    the operator paused the queue (a queued job keeps its place, its ETA means nothing).
    ``reason``: the operator's words on a rejection or cancellation, as plain text cut to a line
    (:func:`kiosk.wording.visitor_reason`); ``failure``: a failed job's error code."""
    board = (places or {}).get(state.vehicle_id or "")
    place = wording.place_words(board)
    error = state.error if state.state in ("failed", "cancelled", "rejected") else None
    reason = wording.visitor_reason(error.reason) if error is not None else None
    failure = error.code if error is not None and state.state == "failed" else None
    return {
        "job_id": state.job_id,
        "state": state.state,
        "final": state.state in FINAL_STATES,
        "label": state.label,
        "queue_position": state.queue_position,
        "eta_s": state.eta_s,
        "vehicle_id": state.vehicle_id,
        "place": place,
        "board": board,
        "attempts": state.attempts,
        "progress": state.progress,
        "metrics": metrics_view(state.metrics),
        "updated_at_s": state.updated_at_s,
        "show_paused": show_paused,
        "reason": reason,
        "failure": failure,
        "status_text": wording.status_text(
            state.state,
            paused=show_paused,
            reason=reason,
            failure=failure,
            queue_position=state.queue_position,
            eta_s=state.eta_s,
            board=board,
            progress=state.progress,
            attempts=state.attempts,
            place=place,
        ),
    }


def ticket_view(job: KioskJob) -> dict[str, Any]:
    """The view of a ticket without a job state: still sending, refused late, or accepted but
    its state not known here yet (looked up from the orchestrator)."""
    refused = job.refusal is not None
    if refused:
        name, text = "refused", job.refusal
    elif job.job_id is not None:
        name, text = "checking", wording.CHECKING
    else:
        name, text = "sending", wording.SENDING
    return {
        "job_id": job.job_id,
        "state": name,
        "final": refused,
        "label": job.label,
        "queue_position": None,
        "eta_s": None,
        "vehicle_id": None,
        "place": None,
        "board": None,
        "refusal": job.refusal_code,
        "attempts": 0,
        "progress": 0.0,
        "metrics": None,
        "updated_at_s": 0.0,
        "show_paused": False,
        "reason": None,
        "failure": None,
        "status_text": text,
    }


class JobBook:
    """Tickets of this kiosk and the latest state seen of any job, both bounded (oldest dropped)."""

    def __init__(self, *, max_jobs: int = 5_000, max_states: int = 5_000) -> None:
        self._jobs: OrderedDict[str, KioskJob] = OrderedDict()
        self._tickets_of: dict[str, str] = {}
        """Orchestrator job id -> ticket."""
        self._codes: dict[str, str] = {}
        """Short code -> ticket."""
        self._states: OrderedDict[str, JobState] = OrderedDict()
        self._phrases: dict[str, dict[int, str]] = {}
        """Phrase id -> its characters' job ids by place, of the states kept."""
        self._max_jobs = max_jobs
        self._max_states = max_states
        self.show_paused = False
        """The show's queue is paused (the latest ``fleet`` snapshot): queued jobs say so."""

    def add(
        self,
        *,
        session_id: str,
        label: str,
        preview: dict[str, Any] | None,
        phrase_size: int = 0,
    ) -> KioskJob:
        """A new ticket with a fresh token and idempotency key (``phrase_size``: of a phrase,
        its characters)."""
        job = KioskJob(
            ticket="t" + secrets.token_hex(8),
            token=secrets.token_urlsafe(24),
            session_id=session_id,
            label=label,
            preview=preview,
            key=secrets.token_urlsafe(24),
            code=new_code(),
            phrase_size=phrase_size,
        )
        while job.code in self._codes:
            job.code = new_code()
        self._jobs[job.ticket] = job
        self._codes[job.code] = job.ticket
        while len(self._jobs) > self._max_jobs:
            _, old = self._jobs.popitem(last=False)
            self._tickets_of.pop(old.job_id or "", None)
            self._codes.pop(old.code, None)
        return job

    def by_code(self, code: str) -> KioskJob | None:
        """The ticket a short code opens (any case, dashes and spaces ignored)."""
        ticket = self._codes.get(normal_code(code))
        return self._jobs.get(ticket) if ticket is not None else None

    def bind(self, ticket: str, job_id: str) -> KioskJob | None:
        """The orchestrator accepted ``ticket`` as ``job_id``."""
        job = self._jobs.get(ticket)
        if job is not None:
            job.job_id = job_id
            self._tickets_of[job_id] = ticket
        return job

    def refuse(self, ticket: str, message: str, code: str = "refused") -> None:
        """The orchestrator refused ``ticket`` (answer to a later try)."""
        job = self._jobs.get(ticket)
        if job is not None:
            job.refusal = message
            job.refusal_code = code

    def drop(self, ticket: str) -> None:
        """Forget a ticket whose refusal the page was told directly."""
        job = self._jobs.pop(ticket, None)
        if job is not None:
            self._codes.pop(job.code, None)

    def get(self, ref: str) -> KioskJob | None:
        """A ticket by its own id or by its orchestrator job id."""
        job = self._jobs.get(ref)
        if job is None and ref in self._tickets_of:
            job = self._jobs.get(self._tickets_of[ref])
        return job

    def ticket_of(self, job_id: str) -> str | None:
        """The ticket following ``job_id``: its own, or its phrase's."""
        ticket = self._tickets_of.get(job_id)
        state = self._states.get(job_id)
        if ticket is None and state is not None and state.phrase is not None:
            ticket = self._tickets_of.get(state.phrase.phrase_id)
        return ticket

    def authorised(self, ref: str, token: str | None) -> KioskJob | None:
        """The ticket when ``token`` is its token, else None (compared in constant time)."""
        job = self.get(ref)
        if job is None or token is None:
            return None
        return job if hmac.compare_digest(job.token.encode(), token.encode()) else None

    def pending_count(self) -> int:
        return sum(1 for job in self._jobs.values() if job.pending)

    def update(self, state: JobState) -> bool:
        """Remember ``state`` unless an older one; True when it changed what we knew."""
        old = self._states.get(state.job_id)
        if old is not None and (state.updated_at_s < old.updated_at_s or old == state):
            return False
        if old is not None and old.state in FINAL_STATES and state.state not in FINAL_STATES:
            return False
        state = _keep_written(old, state)
        if old == state:
            return False
        self._states[state.job_id] = state
        self._states.move_to_end(state.job_id)
        if state.phrase is not None:
            self._phrases.setdefault(state.phrase.phrase_id, {})[state.phrase.index] = state.job_id
        while len(self._states) > self._max_states:
            _, gone = self._states.popitem(last=False)
            if gone.phrase is not None:
                self._phrases.pop(gone.phrase.phrase_id, None)
        return True

    def state(self, job_id: str) -> JobState | None:
        return self._states.get(job_id)

    def characters(self, job: KioskJob) -> list[JobState | None]:
        """The newest states of a phrase ticket's characters in reading order (None: unknown)."""
        ids = self._phrases.get(job.job_id or "", {})
        return [self._states.get(ids.get(i, "")) for i in range(job.phrase_size)]

    def unknown(self, job: KioskJob) -> bool:
        """Whether the ticket is accepted but some of its jobs' states are not known here."""
        if job.job_id is None:
            return False
        if job.phrase_size:
            return None in self.characters(job)
        return job.job_id not in self._states

    def view(self, job: KioskJob, places: Mapping[str, int] | None = None) -> dict[str, Any]:
        """What the page shows of ``job`` now."""
        if job.phrase_size and job.job_id is not None:
            states = self.characters(job)
            if any(s is not None for s in states):
                return phrase_view(job.label, states, places, show_paused=self.show_paused)
        state = self._states.get(job.job_id) if job.job_id is not None else None
        if state is None:
            return ticket_view(job)
        return job_view(state, places, show_paused=self.show_paused)


def _keep_written(old: JobState | None, new: JobState) -> JobState:
    """``new``, with the ink picture of ``old`` when ``new`` has none (only ``jobs/<id>`` and
    some snapshot replies carry it)."""
    if old is None or old.metrics is None or old.metrics.written is None:
        return new
    if new.metrics is None or new.metrics.written is not None:
        return new
    metrics = msgspec.structs.replace(new.metrics, written=old.metrics.written)
    return msgspec.structs.replace(new, metrics=metrics)
