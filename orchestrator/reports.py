"""Agent reports (pure): started / progress / done / failed, idempotent because agents retry;
``ended`` (what was written of a job stopped by something else) changes no job's state
(``orchestrator/job_ends.py``).

A report counts only from the vehicle the job was last given to (the service has already checked
that the report came on that vehicle's own key): ``done`` from any other vehicle is refused
(``not_assigned``), so no agent can finish another's job; from the last holder it is accepted
even after a requeue (the character is written) and whoever took the job over is told to stop,
unless its metrics say nothing was written or the plan was flown in part: then the job fails
(``writing_bounds``, ``orchestrator/unwritten.py``).
``holding``/``started``/``progress`` from the last holder reclaim a job that is back in the queue
and not yet given to another vehicle (a liveliness flap; ``orchestrator/holders.py`` keeps it from
others a while), otherwise the vehicle is told to stop (``not_assigned``); ``holding`` (before
writing: the vehicle renews its lease, ``vehicle_agent/lease.py``) changes nothing else, unless it
carries the planned writing (a *ready* report: the brush goes down once it is acknowledged), whose
receipt is stored as the start of the write fence (``Job.writing_since_s``);
``failed`` is acknowledged and ignored, except a job written in full (``progress`` 1: out of the
bounds, or unmeasured after an agent restart, ``vehicle_agent/results.py``) that still waits for
that vehicle: it fails, and is not written again (a character of a phrase that has begun, not
written in full, goes back to the queue alone instead while it has tries left:
``orchestrator/phrases.py``, and a *ready* report of one whose phrase is not all ready is
answered ``phrase_waits``). A ``failed`` report with ``retry_after_s``
hands the job back to the queue instead of failing it, and so does a ``plan_failed`` one while a
vehicle of another kind may still write the job (the vehicle's kind cannot write it: a width
outside the sponge's range...); it then waits for such a vehicle.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import msgspec

from bus.messages import AgentReport, CommandReply, ErrorInfo, VehicleCommand
from orchestrator import holders, phrases
from orchestrator.core_types import Effects
from orchestrator.job_ends import apply_ended
from orchestrator.jobs import Job, transition, update
from orchestrator.requeue import hand_back, requeue
from orchestrator.unwritten import unwritten
from orchestrator.written import split_written

PLAN_FAILED = "plan_failed"
"""Error code of a job the vehicle's planner refused (``planner.errors.PlannerError.code``)."""
PHRASE_WAITS = "phrase_waits"
"""Error code of a *ready* report not acknowledged yet: the other characters of its phrase are
not all ready (``orchestrator/phrases.py``); the vehicle holds at the start and asks again."""
UNCOUNTED = frozenset({"takeoff_refused", PLAN_FAILED})
"""Handed back without counting an attempt: the vehicle could not start (pre-arm checks), or its
kind cannot write the job and another kind may."""

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def apply_report(book: BookProtocol, rep: AgentReport, eff: Effects, now_s: float) -> CommandReply:
    """Record one report; the reply acknowledges it (or tells the vehicle to stop)."""
    job = book.jobs.get(rep.job_id)
    if job is None:
        return CommandReply(
            ok=False, error=ErrorInfo(code="unknown_job", message=f"no job {rep.job_id}")
        )
    if rep.event == "ended":  # what was written, after the fact: decides nothing
        return apply_ended(book, job, rep, eff, now_s)
    if job.final:
        return CommandReply(ok=True, message=f"job already {job.state}")
    if rep.vehicle_id != job.vehicle_id:
        return _not_assigned(job, rep, eff)
    if rep.event == "done":
        return _done(book, job, rep, eff, now_s)
    owner = job.vehicle_id if job.active else None
    if owner != rep.vehicle_id:
        if rep.event == "failed" and rep.progress >= 1.0 and holders.waits_for(job, now_s):
            return _fail(book, job, rep, eff, now_s, _failure(job, rep))  # written, badly
        if rep.event == "failed":
            return CommandReply(ok=True, message="ignored: the job is not yours any more")
        if not holders.reclaim(book, eff, job, rep.vehicle_id, now_s):
            return _not_assigned(job, rep, eff)
        job = book.jobs[job.job_id]
    if rep.event == "failed":
        return _failed(book, job, rep, eff, now_s)
    if rep.event == "holding":
        book.vehicles[rep.vehicle_id].mismatch_since_s = None
        if rep.planned_duration_s is not None and not phrases.may_write(book, job, now_s):
            info = ErrorInfo(code=PHRASE_WAITS, message=phrases.waiting_for(book, job))
            return CommandReply(ok=False, message=info.message, error=info)
        if rep.planned_duration_s is not None:
            _ready(book, job, rep, eff, now_s)
        return CommandReply(ok=True, message="still yours")
    return _writing(book, job, rep, eff, now_s)


def _not_assigned(job: Job, rep: AgentReport, eff: Effects) -> CommandReply:
    eff.commands.append((rep.vehicle_id, VehicleCommand(command="cancel", job_id=job.job_id)))
    info = ErrorInfo(
        code="not_assigned", message=f"{rep.job_id} is not assigned to {rep.vehicle_id}; stop it"
    )
    return CommandReply(ok=False, error=info)


def _done(
    book: BookProtocol, job: Job, rep: AgentReport, eff: Effects, now_s: float
) -> CommandReply:
    if (why := unwritten(rep.metrics)) is not None:  # the floor under the agent's verdict
        info = ErrorInfo(code="writing_bounds", message=f"written out of bounds: {why}")
        failed = msgspec.structs.replace(rep, event="failed", error=info)
        return _fail(book, job, failed, eff, now_s, _failure(job, failed))
    owner = job.vehicle_id if job.active else None
    planned = rep.planned_duration_s or job.planned_duration_s
    metrics, written = split_written(rep.metrics)
    done = transition(
        job,
        "done",
        now_s,
        vehicle_id=rep.vehicle_id,
        progress=1.0,
        metrics=metrics,
        planned_duration_s=planned,
    )
    book.put(eff, done)
    if written is not None:
        eff.written[job.job_id] = written
    book.event(
        eff,
        now_s,
        "info",
        "job_done",
        f"{job.label} written by {rep.vehicle_id}",
        vehicle_id=rep.vehicle_id,
        job_id=job.job_id,
    )
    if owner is not None and owner != rep.vehicle_id:
        eff.commands.append((owner, VehicleCommand(command="cancel", job_id=job.job_id)))
    _left_on_its_sheet(book, job, eff, now_s)
    eff.fleet_changed = True
    book.assign(eff, now_s)
    return CommandReply(ok=True, message="done recorded")


def _left_on_its_sheet(book: BookProtocol, job: Job, eff: Effects, now_s: float) -> None:
    """``job`` is on its board in full: that board may now wait for the crew's sheet."""
    if job.board_id is None or not book.sheets.written(job.board_id, now_s):
        return
    eff.settings_changed = True
    message = f"{job.board_id}: {job.label} is written; a fresh sheet, then it writes again"
    book.event(
        eff, now_s, "info", "sheet_due", message, vehicle_id=job.vehicle_id, job_id=job.job_id
    )


def _failed(
    book: BookProtocol, job: Job, rep: AgentReport, eff: Effects, now_s: float
) -> CommandReply:
    if rep.retry_after_s is not None:
        return _handed_back(book, job, rep, eff, now_s, rep.retry_after_s)
    if (
        rep.error is not None
        and rep.error.code == PLAN_FAILED
        and book.kinds.refuse(job.job_id, rep.vehicle_id, book.config.vehicles)
    ):
        return _handed_back(book, job, rep, eff, now_s, 0.0)
    if _rewrite_alone(book, job, rep):
        requeue(book, eff, job, now_s, _failure(job, rep) + "; written again alone", lost=False)
        book.assign(eff, now_s)
        return CommandReply(ok=True, message="the character goes back to the queue alone")
    return _fail(book, job, rep, eff, now_s, _failure(job, rep))


def _rewrite_alone(book: BookProtocol, job: Job, rep: AgentReport) -> bool:
    """A character of a phrase that has begun failed before it was written in full, with tries
    left: it is written again alone on its board (the others stay as they are)."""
    return (
        job.phrase is not None
        and rep.progress < 1.0
        and job.counted_attempts < book.config.max_attempts
        and not phrases.not_begun(book, job)
    )


def _failure(job: Job, rep: AgentReport) -> str:
    reason = rep.error.message if rep.error else "no reason given"
    return f"{job.label} failed on {rep.vehicle_id}: {reason}"


def _handed_back(
    book: BookProtocol, job: Job, rep: AgentReport, eff: Effects, now_s: float, retry_after_s: float
) -> CommandReply:
    """The vehicle gave the job back before its brush touched, and is healthy: the job goes back to
    the queue and the vehicle gets no job for ``retry_after_s``. A take-off refusal or a plan its
    kind cannot write (``UNCOUNTED``) does not count as an attempt (a hand-back, bounded apart:
    ``orchestrator/requeue.py``); a safety abort (``not_settled``, ``deviation`` in transit) does,
    so a job that no vehicle can fly fails after ``max_attempts`` rather than go round for ever."""
    view = book.vehicles[rep.vehicle_id]
    view.refused_until_s = max(view.refused_until_s, now_s + max(0.0, retry_after_s))
    reason = rep.error.message if rep.error else "no reason given"
    why = f"{rep.vehicle_id} could not start it: {reason}"
    if rep.error is not None and rep.error.code in UNCOUNTED:
        hand_back(book, eff, job, now_s, why, untouched=True)
    elif job.counted_attempts >= book.config.max_attempts:
        message = f"{job.label} failed on {rep.vehicle_id}: {reason}"
        tries = f"{message}; gave up after {job.counted_attempts} tries"
        return _fail(book, job, rep, eff, now_s, tries)
    else:
        requeue(book, eff, job, now_s, why, lost=False, untouched=True)
    book.assign(eff, now_s)
    return CommandReply(ok=True, message="job back in the queue")


def _fail(
    book: BookProtocol, job: Job, rep: AgentReport, eff: Effects, now_s: float, message: str
) -> CommandReply:
    metrics, written = split_written(rep.metrics)  # written out of its bounds: what it left
    book.put(eff, transition(job, "failed", now_s, error=rep.error, metrics=metrics))
    if written is not None:
        eff.written[job.job_id] = written
    book.event(
        eff, now_s, "alert", "job_failed", message, vehicle_id=rep.vehicle_id, job_id=job.job_id
    )
    if rep.progress >= 1.0:  # written out of its bounds, or unmeasured: on its sheet all the same
        _left_on_its_sheet(book, job, eff, now_s)
    eff.fleet_changed = True
    book.assign(eff, now_s)
    return CommandReply(ok=True, message="failure recorded")


def _ready(book: BookProtocol, job: Job, rep: AgentReport, eff: Effects, now_s: float) -> None:
    """The vehicle is at the start of its writing and asks to write (a *ready* report): from
    the acknowledgement on it may write unheard until the write fence (``bus/fence.py``), so the
    fence's start is stored before the answer, the latest receipt (``Job.writing_since_s``)."""
    since_s = max(job.writing_since_s or now_s, now_s)
    book.put(
        eff, update(job, now_s, writing_since_s=since_s, planned_duration_s=rep.planned_duration_s)
    )


def _writing(
    book: BookProtocol, job: Job, rep: AgentReport, eff: Effects, now_s: float
) -> CommandReply:
    book.vehicles[rep.vehicle_id].mismatch_since_s = None
    if job.state == "assigned":
        book.event(
            eff,
            now_s,
            "info",
            "job_writing",
            f"{rep.vehicle_id} writes {job.label}",
            vehicle_id=rep.vehicle_id,
            job_id=job.job_id,
        )
        eff.fleet_changed = True
    writing = transition(
        job,
        "writing",
        now_s,
        planned_duration_s=rep.planned_duration_s or job.planned_duration_s,
        progress=max(job.progress, min(1.0, rep.progress)),
        writing_since_s=job.writing_since_s if job.writing_since_s is not None else now_s,
    )
    book.put(eff, writing)  # progress alone (twice a second per writer) is not stored
    return CommandReply(ok=True, message=f"{rep.event} recorded")
