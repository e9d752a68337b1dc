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
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import ErrorInfo
from orchestrator.core_types import Effects
from orchestrator.jobs import Job, transition, update

if TYPE_CHECKING:
    from orchestrator.core import Book


def requeue(
    book: Book,
    eff: Effects,
    job: Job,
    now_s: float,
    reason: str,
    *,
    lost: bool,
    wait_for_holder: bool = False,
) -> None:
    """Take an active job back: queued again, or failed after too many lost attempts (or
    hand-backs, :func:`hand_back`);
    ``wait_for_holder``: its vehicle was lost, and the job waits for it a while
    (``orchestrator/holders.py``)."""
    info = ErrorInfo(code="vehicle_lost" if lost else "requeued", message=reason)
    if job.board_id is not None and (job.state == "writing" or job.progress > 0):
        book.dirty_boards.add(job.board_id)
        eff.settings_changed = True
        book.event(
            eff,
            now_s,
            "alert",
            "board_dirty",
            f"{job.board_id} half-written by {job.label}: fresh sheet needed",
            vehicle_id=job.vehicle_id,
            job_id=job.job_id,
        )
    gave_up = _gave_up(book, job, lost)
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
    hold_until_s = now_s + book.config.lost_job_hold_s if wait_for_holder else None
    if hold_until_s is not None:
        reason = f"{reason}; waits {book.config.lost_job_hold_s:.0f} s for it to come back"
    queued = transition(
        job,
        "queued",
        now_s,
        error=info,
        progress=0.0,
        assigned_at_s=None,
        holder_hold_until_s=hold_until_s,
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


def hand_back(book: Book, eff: Effects, job: Job, now_s: float, reason: str) -> None:
    """Take an active job back without counting its attempt (see the module docstring): queued
    again, or failed once it has been handed back ``max_handbacks`` times."""
    requeue(book, eff, update(job, now_s, handbacks=job.handbacks + 1), now_s, reason, lost=False)


def _gave_up(book: Book, job: Job, lost: bool) -> str | None:
    """Why a job taken back fails instead of going back to the queue (None: it goes back)."""
    if lost and job.counted_attempts >= book.config.max_attempts:
        return f"{job.counted_attempts} attempts"
    if job.handbacks >= book.config.max_handbacks:
        return f"{job.handbacks} hand-backs"
    return None
