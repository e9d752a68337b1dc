"""A job and the transitions it may make (pure).

    submitted -> awaiting_approval (moderated show) -> queued -> assigned -> writing -> done
                          |                               ^          |          |  -> failed
                          v                               +--requeue-+----------+  -> cancelled
                       rejected                          (vehicle lost, dropped, landed)

``done``, ``failed``, ``cancelled`` and ``rejected`` are final. A requeued job keeps its submission
order (``seq``) and priority, so it goes back to where it was in the queue. ``queued -> done``
happens when a vehicle that was taken for lost reports the job written after all.
"""

from __future__ import annotations

from typing import Any, Literal

import msgspec

from bus.messages import ErrorInfo, JobMetrics, JobState, JobStateName, PhrasePlace, SubmitRequest

FINAL_STATES: frozenset[str] = frozenset({"done", "failed", "cancelled", "rejected"})
ACTIVE_STATES: frozenset[str] = frozenset({"assigned", "writing"})
WAITING_STATES: frozenset[str] = frozenset({"awaiting_approval", "queued"})

TRANSITIONS: dict[str, frozenset[str]] = {
    "submitted": frozenset({"awaiting_approval", "queued", "rejected"}),
    "awaiting_approval": frozenset({"queued", "rejected", "cancelled"}),
    "queued": frozenset({"assigned", "cancelled", "failed", "done"}),
    "assigned": frozenset({"writing", "queued", "done", "failed", "cancelled"}),
    "writing": frozenset({"queued", "done", "failed", "cancelled"}),
    "done": frozenset(),
    "failed": frozenset(),
    "cancelled": frozenset(),
    "rejected": frozenset(),
}
"""Allowed next states of every state."""


class TransitionError(ValueError):
    """A job was asked to move to a state it cannot reach from where it is."""


class Job(msgspec.Struct, frozen=True, kw_only=True):
    """Everything the orchestrator keeps about one job (stored as JSON in SQLite)."""

    job_id: str
    """Unique id, also in the job's Zenoh key."""
    seq: int
    """Submission order (1, 2, ...); FIFO within a priority."""
    state: JobStateName
    """Where the job is in its life."""
    kind: Literal["text", "strokes"]
    """Typed text or a strokes document."""
    text: str | None = None
    """The typed text (kind ``text``)."""
    strokes: dict[str, Any] | None = None
    """The strokes document (kind ``strokes``)."""
    label: str
    """Short human label: the text, or ``drawing (N strokes)``."""
    client_id: str
    """Who handed it in."""
    priority: int = 0
    """Higher first."""
    created_at_s: float
    """Unix time of the submission, [s]."""
    updated_at_s: float
    """Unix time of the last change, [s]."""
    vehicle_id: str | None = None
    """Vehicle writing it (assigned/writing), or the last one that did."""
    board_id: str | None = None
    """Board of that vehicle."""
    assigned_at_s: float | None = None
    """Orchestrator time of the latest assignment (or of the restart that found it active), [s]."""
    attempts: int = 0
    """Number of assignments so far."""
    handbacks: int = 0
    """Of those, how many were taken back for a reason not the job's own, not counted against
    ``max_attempts`` (``orchestrator/requeue.py``)."""
    estimate_s: float = 30.0
    """Expected duration of writing in sim time, [s] (estimate, then the planner's)."""
    planned_duration_s: float | None = None
    """Duration of the planned trajectory reported by the vehicle, [s]."""
    progress: float = 0.0
    """Fraction written, 0..1."""
    metrics: JobMetrics | None = None
    """Result metrics from the vehicle (done)."""
    error: ErrorInfo | None = None
    """Why it failed, was rejected or requeued last."""
    idempotency_key: str | None = None
    """The submitter's key for this submission (a repeat with it gets this job, not a new one)."""
    holder_hold_until_s: float | None = None
    """Queued after its vehicle (``vehicle_id``) was lost: only that vehicle may take it before
    this Unix time, [s] (``orchestrator/holders.py``)."""
    writing_since_s: float | None = None
    """Unix time, [s], the orchestrator last heard ``vehicle_id`` ask to write this attempt (its
    latest *ready* report, or its ``started`` one if none came); None before, and once another
    attempt begins. With ``planned_duration_s`` it bounds how long that vehicle may write it
    unheard (``orchestrator/holders.py``, ``writing_fence_s``)."""
    submitted_by: str | None = None
    """The identity that submitted it on the bus (its certificate's common name, read from the
    submit key: ``orchestrator/quotas.py``); None for jobs stored before it was kept."""
    phrase: PhrasePlace | None = None
    """Its place in a phrase written together (``orchestrator/phrases.py``); None: alone."""
    rewrite_alone: bool = False
    """A character of a phrase that had begun, back in the queue: written again alone, on its
    own board (``board_id``), and released at once."""

    @property
    def counted_attempts(self) -> int:
        """Assignments that count against ``max_attempts`` (hand-backs do not)."""
        return self.attempts - self.handbacks

    @property
    def final(self) -> bool:
        return self.state in FINAL_STATES

    @property
    def active(self) -> bool:
        """Assigned to a vehicle or being written."""
        return self.state in ACTIVE_STATES

    @property
    def sort_key(self) -> tuple[int, int]:
        """Queue order: higher priority first, then submission order."""
        return (-self.priority, self.seq)


def new_job(
    job_id: str,
    seq: int,
    request: SubmitRequest,
    *,
    text: str | None,
    strokes: dict[str, Any] | None,
    label: str,
    estimate_s: float,
    now_s: float,
    idempotency_key: str | None,
    submitted_by: str | None,
    phrase: PhrasePlace | None = None,
) -> Job:
    """A job ``request`` hands in, as submitted at ``now_s`` [s] (submission order ``seq``,
    expected to take ``estimate_s`` [s]): of kind ``text`` when it has ``text``, else
    ``strokes``. A job alone takes the request's text, strokes and key; a phrase's character
    its own text and place, and the key only for the first (``orchestrator/phrase_intake.py``)."""
    return Job(
        job_id=job_id,
        seq=seq,
        state="submitted",
        kind="text" if text is not None else "strokes",
        text=text,
        strokes=strokes,
        label=label,
        client_id=request.client_id,
        priority=request.priority,
        created_at_s=now_s,
        updated_at_s=now_s,
        estimate_s=estimate_s,
        idempotency_key=idempotency_key,
        submitted_by=submitted_by,
        phrase=phrase,
    )


def transition(job: Job, state: JobStateName, now_s: float, **changes: Any) -> Job:
    """``job`` moved to ``state`` (with other fields changed); raises :class:`TransitionError`."""
    if state != job.state and state not in TRANSITIONS[job.state]:
        raise TransitionError(f"job {job.job_id} cannot go from {job.state} to {state}")
    return msgspec.structs.replace(job, state=state, updated_at_s=now_s, **changes)


def update(job: Job, now_s: float, **changes: Any) -> Job:
    """``job`` with fields changed, state unchanged."""
    return msgspec.structs.replace(job, updated_at_s=now_s, **changes)


def to_state(
    job: Job,
    *,
    queue_position: int | None = None,
    eta_s: float | None = None,
    with_strokes: bool = False,
) -> JobState:
    """The wire view of a job; ``with_strokes``: its strokes document too while it is waiting
    (awaiting approval or queued), for previews."""
    waiting = with_strokes and job.state in WAITING_STATES
    return JobState(
        job_id=job.job_id,
        state=job.state,
        label=job.label,
        kind=job.kind,
        client_id=job.client_id,
        created_at_s=job.created_at_s,
        updated_at_s=job.updated_at_s,
        priority=job.priority,
        vehicle_id=job.vehicle_id,
        queue_position=queue_position,
        eta_s=eta_s,
        planned_duration_s=job.planned_duration_s,
        progress=job.progress,
        attempts=job.attempts,
        metrics=job.metrics,
        error=job.error,
        strokes=job.strokes if waiting else None,
        phrase=job.phrase,
    )
