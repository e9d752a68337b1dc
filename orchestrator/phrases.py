"""Phrases written together (pure): a short phrase is one job per character, on adjacent boards.

A visitor's phrase (``SubmitRequest.phrase``, at most as many characters as the show has boards
in its row) becomes one job per character, each with its :class:`PhrasePlace`; the phrase's id
is its first character's job id. The row is the show's boards as the show file lists them, left
to right as the public sees them (the kiosk names boards by that place too).

- **Dispatch** (``orchestrator/assignment.py``): the queued characters of a phrase are given in
  one decision to ready vehicles on adjacent boards, in reading order (the leftmost such window),
  or none is. Jobs behind a phrase that waits take no vehicle on a board the phrase could use
  (else it might never find its boards free together); a phrase that no window of usable
  vehicles could ever take holds nothing back.
- **Start** (:func:`may_write`): a vehicle begins writing only once its *ready* report is
  acknowledged (``vehicle_agent/lease.py``); a character's is acknowledged only when every
  character dispatched with it has reported ready, so the vehicles hold at the start of their
  writing and begin within one ready period (``lost_after_s / 3``) of each other.
- **Failure** (``orchestrator/requeue.py``): a character taken back before its phrase began takes
  the others dispatched with it back too (cancelled on their vehicles, handed back uncounted), so
  the phrase is dispatched together again; after it began, the character is written again alone
  on its own board (``Job.rewrite_alone``), its sheet changed first if it was half-written.
- **Ending before the start** (:func:`ended_unbegun`): a character that fails (no vehicle could
  write it, or it was lost too often) or is cancelled before its phrase began ends the phrase:
  a phrase is written whole or not at all, as its visitor handed it in and as the operator
  approved it, never with a hole or shifted along the row. Its other characters end with it
  (their vehicles told to cancel): ``cancelled`` with the operator's reason when it was
  cancelled, else ``failed`` with :data:`PHRASE_INCOMPLETE` naming the character and why; the
  operator gets one alert, and the visitor's ticket says the phrase could not be written.
- **ETAs** (``orchestrator/fleet.py``): the characters of a phrase start at the earliest time a
  window of adjacent boards has a vehicle free for each, and the boards it could use take no job
  behind it before then.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from bus.messages import ErrorInfo, VehicleCommand
from orchestrator.jobs import Job, transition
from orchestrator.phrase_rows import phrase_index, together

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol
    from orchestrator.core_types import CoreConfig, Effects

PHRASE_INCOMPLETE = "phrase_incomplete"
"""Error code of a character ended because another of its phrase could not be written before
the phrase began (:func:`ended_unbegun`)."""


def board_row(config: CoreConfig) -> list[str]:
    """The row of boards left to right: the show's boards in its order, or, when none is
    declared apart, the boards in the order the vehicles name them."""
    declared = [board_id for board_id, _ in config.boards]
    return list(dict.fromkeys(declared or (v.board_id for v in config.vehicles)))


def siblings(book: BookProtocol, job: Job) -> list[Job]:
    """The other characters of ``job``'s phrase held by the Book, started together with it."""
    phrase = job.phrase
    if phrase is None:
        return []
    return [
        j
        for j in book.jobs.values()
        if j.job_id != job.job_id
        and together(j)
        and j.phrase is not None
        and j.phrase.phrase_id == phrase.phrase_id
    ]


def began(job: Job) -> bool:
    """Whether ``job``'s vehicle was let write it (its *ready* report acknowledged) or wrote."""
    return job.writing_since_s is not None or job.state in ("writing", "done") or job.progress > 0


def not_begun(book: BookProtocol, job: Job) -> bool:
    """Whether ``job`` is a character of a phrase of which no character has begun: taken back,
    it takes the others back with it."""
    return together(job) and not began(job) and not any(began(j) for j in siblings(book, job))


def may_write(book: BookProtocol, job: Job, now_s: float) -> bool:
    """A *ready* report of ``job`` (active, from its vehicle) came at ``now_s``: whether to
    acknowledge it (the vehicle then begins writing). Yes for a job alone or a phrase that has
    begun; else only once every character dispatched with it has reported ready within
    ``lost_after_s`` (older: its vehicle may have given up)."""
    if not together(job):
        return True
    others = [j for j in siblings(book, job) if not j.final]
    if any(began(j) for j in others):
        return True
    ready = book.phrase_ready
    for stale in [k for k in ready if k not in book.jobs or not book.jobs[k].active]:
        del ready[stale]
    ready[job.job_id] = (job.attempts, now_s)
    fresh_s = now_s - book.config.lost_after_s
    if not all(
        j.active and ready.get(j.job_id, (-1, -math.inf)) >= (j.attempts, fresh_s) for j in others
    ):
        return False
    for j in (job, *others):
        ready.pop(j.job_id, None)
    return True


def waiting_for(book: BookProtocol, job: Job) -> str:
    """Why a *ready* report of ``job`` is not acknowledged yet, in one line."""
    late = [
        j.label for j in siblings(book, job) if not j.final and j.job_id not in book.phrase_ready
    ]
    return f"{job.label} waits for {' '.join(late) or 'its phrase'} to start together"


def ended_unbegun(book: BookProtocol, eff: Effects, job: Job) -> None:
    """``job`` has just ended (``Book.put``): if it is a character of a phrase that had not
    begun, ended unwritten (failed or cancelled), its phrase's other characters end with it."""
    if job.state not in ("failed", "cancelled") or not together(job):
        return
    if job.error is not None and job.error.code == PHRASE_INCOMPLETE:
        return  # one of those ended here
    others = [j for j in siblings(book, job) if not j.final]
    if began(job) or not others or any(began(j) for j in siblings(book, job)):
        return
    assert job.phrase is not None
    now_s, why = job.updated_at_s, job.error.message if job.error else "no reason given"
    if job.state == "cancelled":  # the operator's reason, for the visitor
        message = f"{job.label} of its phrase was cancelled: written whole or not at all"
        reason = job.error.reason if job.error else None
    else:
        message = f"{job.label} of its phrase could not be written ({why}): written whole or not"
        reason = None
    info = ErrorInfo(code=PHRASE_INCOMPLETE, message=message, reason=reason)
    for other in sorted(others, key=phrase_index):
        if other.active and other.vehicle_id is not None:
            stop = VehicleCommand(command="cancel", job_id=other.job_id)
            eff.commands.append((other.vehicle_id, stop))
        book.put(eff, transition(other, job.state, now_s, error=info))
    text = "".join(j.label for j in sorted([job, *others], key=phrase_index))
    book.event(
        eff,
        now_s,
        "alert" if job.state == "failed" else "info",
        "phrase_ended",
        f"phrase {text}: {job.label} {job.state} before it began ({why}); the other"
        f" {len(others)} end with it",
        job_id=job.phrase.phrase_id,
    )
    eff.fleet_changed = True
