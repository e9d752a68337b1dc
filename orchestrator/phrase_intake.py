"""A phrase handed in (pure): one job per character, with its place (``orchestrator/phrases.py``).

The submission was validated by the caller (``orchestrator/submissions.py``: plain characters,
no more than the row has boards) and its quotas counted as its characters. All its jobs are made
at once or none: a full queue refuses the whole phrase.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

from bus.messages import ErrorInfo, JobStateName, PhrasePlace, SubmitReply, SubmitRequest
from orchestrator.core_types import Effects
from orchestrator.jobs import new_job, transition
from orchestrator.quotas import is_operator

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def submit(
    book: BookProtocol,
    job_ids: Sequence[str],
    request: SubmitRequest,
    estimates_s: Sequence[float],
    now_s: float,
    submitted_by: str | None,
) -> tuple[SubmitReply, Effects]:
    """Make the phrase's jobs (``job_ids[i]`` writes its ``i``-th character, in about
    ``estimates_s[i]``); the reply names the first, whose id is the phrase's. A repeated
    ``idempotency_key`` answers with the phrase it made first."""
    eff = Effects()
    key = request.idempotency_key
    first = book.by_key.get((request.client_id, key)) if key is not None else None
    if first is not None and first in book.jobs:
        return book.submit_reply(first, now_s), eff
    characters = list(request.text or "")
    if len(job_ids) != len(characters) or len(estimates_s) != len(characters):
        raise ValueError(f"{len(characters)} characters need as many job ids and estimates")
    if any(job_id in book.jobs for job_id in job_ids):
        raise ValueError(f"duplicate job id among {list(job_ids)}")
    full = _full(book, len(characters), submitted_by)
    if full is not None:
        return SubmitReply(ok=False, error=full), eff
    state: JobStateName = "awaiting_approval" if book.config.moderation else "queued"
    for index, (job_id, char, estimate_s) in enumerate(
        zip(job_ids, characters, estimates_s, strict=True)
    ):
        job = new_job(
            job_id,
            book.next_seq,
            request,
            text=char,
            strokes=None,
            label=char,
            estimate_s=estimate_s,
            now_s=now_s,
            idempotency_key=key if index == 0 else None,
            submitted_by=submitted_by,
            phrase=PhrasePlace(phrase_id=job_ids[0], index=index, size=len(characters)),
        )
        book.next_seq += 1
        book.put(eff, transition(job, state, now_s))
    if key is not None:
        book.by_key[(request.client_id, key)] = job_ids[0]
    message = (
        f"phrase {''.join(characters)} ({len(characters)} characters) from {request.client_id}"
    )
    book.event(eff, now_s, "info", "job_submitted", message, job_id=job_ids[0])
    book.assign(eff, now_s)
    book.settle(eff, now_s)
    return book.submit_reply(job_ids[0], now_s), eff


def _full(book: BookProtocol, count: int, submitted_by: str | None) -> ErrorInfo | None:
    """Why the state the phrase's jobs enter has no room for ``count`` more (None: it has), as
    ``job_intake._full`` says for one job."""
    if submitted_by is not None and is_operator(submitted_by):
        return None
    moderated = book.config.moderation
    state = "awaiting_approval" if moderated else "queued"
    limit = book.config.max_awaiting if moderated else book.config.max_queue
    if book.job_counts[state] + count <= limit:
        return None
    waiting = "jobs awaiting approval" if moderated else "jobs queued"
    return ErrorInfo(
        code="queue_full",
        message=f"the queue has no room for {count} characters ({limit} {waiting})",
    )
