"""A job handed in (pure): one drawing or text, if the queue has room, then its planned durations.

The submission was validated by the caller (its glyph parsed, ``orchestrator/submissions.py``)
and its identity's quotas checked (``orchestrator/quotas.py``). A phrase, one job per character,
is handed in by ``orchestrator/phrase_intake.py``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import ErrorInfo, SubmitReply, SubmitRequest
from orchestrator.core_types import Effects
from orchestrator.jobs import new_job, transition, update
from orchestrator.kinds import KindPlans
from orchestrator.quotas import is_operator

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def submit(
    book: BookProtocol,
    job_id: str,
    request: SubmitRequest,
    label: str,
    estimate_s: float,
    now_s: float,
    submitted_by: str | None,
) -> tuple[SubmitReply, Effects]:
    """Make the job ``request`` asks for, or refuse it when the queue is full, as
    ``Book.submit`` says."""
    eff = Effects()
    key = request.idempotency_key
    first = book.by_key.get((request.client_id, key)) if key is not None else None
    if first is not None and first in book.jobs:
        return book.submit_reply(first, now_s), eff
    if job_id in book.jobs:
        raise ValueError(f"duplicate job id {job_id}")
    full = _full(book, submitted_by)
    if full is not None:
        return SubmitReply(ok=False, error=full), eff
    job = new_job(
        job_id,
        book.next_seq,
        request,
        text=request.text,
        strokes=request.strokes,
        label=label,
        estimate_s=estimate_s,
        now_s=now_s,
        idempotency_key=key,
        submitted_by=submitted_by,
    )
    book.next_seq += 1
    if key is not None:
        book.by_key[(request.client_id, key)] = job_id
    job = transition(job, "awaiting_approval" if book.config.moderation else "queued", now_s)
    book.put(eff, job)
    book.event(
        eff, now_s, "info", "job_submitted", f"{label} from {request.client_id}", job_id=job_id
    )
    book.assign(eff, now_s)
    book.settle(eff, now_s)
    return book.submit_reply(job_id, now_s), eff


def _full(book: BookProtocol, submitted_by: str | None) -> ErrorInfo | None:
    """Why the state a new job enters takes no more (None: there is room). Jobs awaiting
    approval count apart from the queue (``max_awaiting``): unmoderated jobs never block
    approved ones. The operator's own submissions are never refused."""
    if submitted_by is not None and is_operator(submitted_by):
        return None
    moderated = book.config.moderation
    state = "awaiting_approval" if moderated else "queued"
    limit = book.config.max_awaiting if moderated else book.config.max_queue
    if book.job_counts[state] < limit:
        return None
    waiting = "jobs awaiting approval" if moderated else "jobs queued"
    return ErrorInfo(code="queue_full", message=f"the queue is full ({limit} {waiting})")


def set_estimate(book: BookProtocol, job_id: str, plans: KindPlans, now_s: float) -> Effects:
    """Take what each kind's planner made of a job (``Book.set_estimate``); settled."""
    eff = Effects()
    job = book.jobs.get(job_id)
    if job is not None and not job.final:
        if plans.refused:
            book.kinds.refuse_kinds(job_id, plans.refused, book.config.vehicles)
        by_kind = plans.durations_s
        if by_kind:
            first = by_kind.get(book.config.vehicles[0].kind, min(by_kind.values()))
            book.kinds.estimates[job_id] = dict(by_kind)
            book.put(eff, update(job, now_s, estimate_s=first))
    return book.settle(eff, now_s)
