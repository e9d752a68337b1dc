"""Bulk moderation (pure): ``reject`` or ``cancel`` of many waiting jobs in one operator command.

A flood of submissions (one client handing in hundreds of junk characters) is undone with one
command: every waiting job of a client (``client_id``: the id a submission declared, or the
certificate it came with, e.g. ``submitter@booth``, whatever ids that one declared), or a
selection (``job_ids``). Only jobs
that no vehicle has are touched, so a bulk command never stops a flight:

- ``reject`` takes jobs awaiting approval (a queued job was approved already: ``cancel`` it),
  and with a character of a phrase every character of it awaiting approval (a phrase is
  moderated as one submission);
- ``cancel`` takes jobs awaiting approval and queued ones, except a queued job that waits for
  the lost vehicle that had it (``orchestrator/holders.py``): that vehicle may be writing it;
- assigned and writing jobs are left to the one-job ``cancel``, which tells their vehicle to stop:
  a vehicle given a job may already be taking off with it.

Each job taken moves as the one-job command moves it (state, ``error`` with the reason, its own
``operator`` line in the event log, published); the reply names them (``job_ids``) and the jobs
left as they were, with why (``skipped``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import ErrorInfo, JobStateName, OperatorCommand, OperatorReply, SkippedJob
from orchestrator.holders import waits_for
from orchestrator.jobs import transition

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol
    from orchestrator.core_types import Effects
    from orchestrator.jobs import Job

SHOWN_IDS = 5
"""Skipped jobs named in a reply's one-line ``message`` (all are in ``skipped``)."""


def is_bulk(cmd: OperatorCommand) -> bool:
    """Whether the command names its jobs by ``job_ids`` or ``client_id``."""
    return cmd.job_ids is not None or cmd.client_id is not None


def _why_not(job: Job, command: str, now_s: float) -> str | None:
    """Why a bulk ``reject`` / ``cancel`` leaves ``job`` as it is (None: it takes it)."""
    if job.state == "awaiting_approval":
        return None
    if job.state == "queued":
        if command == "reject":
            return "queued (approved already: cancel it)"
        holder = waits_for(job, now_s)
        return None if holder is None else f"waits for {holder}, which may be writing it"
    if job.active:
        return f"{job.state} on {job.vehicle_id} (cancel it alone: its vehicle stops)"
    return f"already {job.state}"


def _chosen(
    book: BookProtocol, cmd: OperatorCommand
) -> list[tuple[str, Job | None]] | OperatorReply:
    """The jobs the command names, in submission order (unknown ids last), or why none."""
    if cmd.job_id is not None or (cmd.job_ids is not None and cmd.client_id is not None):
        return _refused("invalid", f"{cmd.command} takes one of job_id, job_ids, client_id")
    if cmd.client_id is not None:
        whose = cmd.client_id
        mine = [j for j in book.jobs.values() if whose in (j.client_id, j.submitted_by)]
        if not mine:
            return _refused("unknown_client", f"no job of client {cmd.client_id!r}", "client_id")
        return [(j.job_id, j) for j in sorted(mine, key=lambda j: j.seq) if not j.final]
    ids = list(dict.fromkeys(cmd.job_ids or ()))
    if cmd.command == "reject":  # a phrase is moderated as one submission
        ids = list(dict.fromkeys(
            k for i in ids for k in [i, *(j.job_id for j in _phrase_of(book, i))]
        ))  # fmt: skip
    known = sorted((book.jobs[i] for i in ids if i in book.jobs), key=lambda j: j.seq)
    return [(j.job_id, j) for j in known] + [(i, None) for i in ids if i not in book.jobs]


def moderated_together(book: BookProtocol, job: Job) -> list[Job]:
    """What one approval or rejection of ``job`` decides: a phrase is moderated as one
    submission (its characters are dispatched together), so every character of its phrase
    awaiting approval, in reading order; else ``job`` alone."""
    if job.phrase is None:
        return [job]
    phrase_id = job.phrase.phrase_id
    return sorted(
        (
            j
            for j in book.jobs.values()
            if j.phrase is not None
            and j.phrase.phrase_id == phrase_id
            and j.state == "awaiting_approval"
        ),
        key=lambda j: j.phrase.index if j.phrase is not None else 0,
    )


def _phrase_of(book: BookProtocol, job_id: str) -> list[Job]:
    """The characters awaiting approval of the phrase of ``job_id`` (none: not a phrase)."""
    job = book.jobs.get(job_id)
    return moderated_together(book, job) if job is not None and job.phrase is not None else []


def _refused(code: str, message: str, field: str = "job_ids") -> OperatorReply:
    return OperatorReply(
        ok=False, message=message, error=ErrorInfo(code=code, message=message, field=field)
    )


def apply_bulk(
    book: BookProtocol, cmd: OperatorCommand, eff: Effects, now_s: float
) -> OperatorReply:
    """``reject`` or ``cancel`` every waiting job ``cmd`` names (see the module)."""
    chosen = _chosen(book, cmd)
    if isinstance(chosen, OperatorReply):
        return chosen
    final: JobStateName = "rejected" if cmd.command == "reject" else "cancelled"
    note = cmd.reason or f"{final} by {cmd.operator}"
    done: list[str] = []
    skipped: list[SkippedJob] = []
    for job_id, job in chosen:
        why = "no such job" if job is None else _why_not(job, cmd.command, now_s)
        if job is None or why is not None:
            state = None if job is None else job.state
            skipped.append(SkippedJob(job_id=job_id, state=state, reason=why or ""))
            continue
        info = ErrorInfo(code=final, message=note, reason=cmd.reason or None)
        book.put(eff, transition(job, final, now_s, error=info))
        book.event(
            eff,
            now_s,
            "info",
            "operator",
            f"{cmd.operator}: {cmd.command} {job_id}" + (f" ({cmd.reason})" if cmd.reason else ""),
            job_id=job_id,
        )
        done.append(job_id)
    eff.fleet_changed = eff.fleet_changed or bool(done)
    return OperatorReply(
        ok=True, message=_summary(cmd, final, done, skipped), job_ids=done, skipped=skipped
    )


def _summary(cmd: OperatorCommand, final: str, done: list[str], skipped: list[SkippedJob]) -> str:
    """One line: how many jobs, whose, and the first few left as they were."""
    whose = f" of client {cmd.client_id!r}" if cmd.client_id is not None else ""
    line = f"{final} {len(done)} job(s){whose}"
    if skipped:
        named = ", ".join(f"{s.job_id} ({s.reason})" for s in skipped[:SHOWN_IDS])
        more = f", +{len(skipped) - SHOWN_IDS} more" if len(skipped) > SHOWN_IDS else ""
        line += f"; {len(skipped)} skipped: {named}{more}"
    return line
