"""A job taken back from its vehicle (pure): queued again, or failed after too many attempts.

Every rule that takes an active job back (a lost vehicle, a refused or unanswered assignment, a
vehicle that could not start, an operator's ``land``/``estop``) does it here: a board left
half-written is marked dirty (no job there until a fresh sheet), a lost vehicle's job fails after
``CoreConfig.max_attempts`` and may wait for that vehicle a while (``orchestrator/holders.py``).

A job taken back for a reason that is not its own (:func:`hand_back`: its vehicle refused it,
could not take off, is of a kind that cannot write it, or is present and healthy but no longer
names it: its lease ran out under load) does not count the attempt: under CPU overload or on a
poor link, jobs with nothing wrong with them failed after three such give-ups. Those hand-backs
are bounded apart, by ``CoreConfig.max_handbacks``, so that no job goes round for ever.

A character of a phrase that has not begun takes the others dispatched with it back too; one
whose phrase has begun is written again alone, on its board (``orchestrator/phrases.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import ErrorInfo, VehicleCommand
from orchestrator import phrases
from orchestrator.core_types import Effects
from orchestrator.holders import hold_until_s, left_half_written
from orchestrator.jobs import Job, transition, update

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def requeue(
    book: BookProtocol,
    eff: Effects,
    job: Job,
    now_s: float,
    reason: str,
    *,
    lost: bool,
    wait_for_holder: bool = False,
    untouched: bool = False,
) -> None:
    """Take an active job back: queued again, or failed after too many lost attempts (or
    hand-backs, :func:`hand_back`);
    ``wait_for_holder``: its vehicle was lost, and the job waits for it a while
    (``orchestrator/holders.py``); ``untouched``: its vehicle handed it back saying its brush
    never touched the board (e.g. ``not_settled`` after its *ready* report), so the board is as
    it was and needs no fresh sheet."""
    together = phrases.not_begun(book, job)  # its phrase goes back with it, whoever held it
    wait_for_holder = wait_for_holder and not together
    info = ErrorInfo(code="vehicle_lost" if lost else "requeued", message=reason)
    begun = not untouched and (
        job.state == "writing" or job.progress > 0 or job.writing_since_s is not None
    )
    if begun and not wait_for_holder:  # a lost holder may be writing on: see holders.py
        left_half_written(book, eff, job, now_s)
    gave_up = _gave_up(book, job, lost and not (wait_for_holder and begun))
    if gave_up is not None:
        book.put(eff, transition(job, "failed", now_s, error=info, progress=0.0))
        book.event(
            eff,
            now_s,
            "alert",
            "job_failed",
            f"{job.label}: {reason}; gave up after {gave_up}",
            vehicle_id=job.vehicle_id,
            job_id=job.job_id,
        )
        return
    until_s = hold_until_s(book.config, job, now_s) if wait_for_holder else None
    if until_s is not None and job.writing_since_s is not None:
        maybe = "it may be writing it, or have written it"
        reason = f"{reason}; waits for it to say how it ended ({maybe})"
    elif until_s is not None:
        reason = f"{reason}; waits {until_s - now_s:.0f} s for it to come back"
    queued = transition(
        job,
        "queued",
        now_s,
        error=info,
        progress=job.progress if until_s is not None else 0.0,
        assigned_at_s=None,
        holder_hold_until_s=until_s,
        writing_since_s=job.writing_since_s if until_s is not None else None,
        rewrite_alone=job.rewrite_alone or (job.phrase is not None and not together),
    )
    book.put(eff, queued)
    book.event(
        eff,
        now_s,
        "warning",
        "job_requeued",
        f"{job.label}: {reason}",
        vehicle_id=job.vehicle_id,
        job_id=job.job_id,
    )
    eff.fleet_changed = True
    if together:
        _with_its_phrase(book, eff, job, now_s)


def _with_its_phrase(book: BookProtocol, eff: Effects, job: Job, now_s: float) -> None:
    """A character of a phrase that has not begun went back to the queue: so do the others
    dispatched with it (their vehicles told to stop), to be dispatched together again."""
    for other in phrases.siblings(book, job):
        if other.active and other.vehicle_id is not None:
            stop = VehicleCommand(command="cancel", job_id=other.job_id)
            eff.commands.append((other.vehicle_id, stop))
            why = f"{job.label} of its phrase went back to the queue; they start together"
            hand_back(book, eff, other, now_s, why)


def hand_back(
    book: BookProtocol,
    eff: Effects,
    job: Job,
    now_s: float,
    reason: str,
    *,
    untouched: bool = False,
) -> None:
    """Take an active job back without counting its attempt (see the module docstring): queued
    again, or failed once it has been handed back ``max_handbacks`` times (``untouched``: as
    :func:`requeue`)."""
    again = update(job, now_s, handbacks=job.handbacks + 1)
    requeue(book, eff, again, now_s, reason, lost=False, untouched=untouched)


def _gave_up(book: BookProtocol, job: Job, lost: bool) -> str | None:
    """Why a job taken back fails instead of going back to the queue (None: it goes back)."""
    if lost and job.counted_attempts >= book.config.max_attempts:
        return f"{job.counted_attempts} attempts"
    if job.handbacks >= book.config.max_handbacks:
        return f"{job.handbacks} hand-backs"
    return None
