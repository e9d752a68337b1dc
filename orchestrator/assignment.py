"""Giving queued jobs to vehicles (pure), and what an agent's answer to an assignment does.

Jobs go in queue order (priority, then submission) to vehicles that are ready
(``orchestrator/fleet.py:ready_for_job``), whose board is free and clean, and whose kind can
write the job (``orchestrator/kinds.py``); a job waiting for its lost vehicle goes to nobody
(``orchestrator/holders.py``). A refused or unanswered assignment puts the job back without
counting the attempt (a hand-back, ``orchestrator/requeue.py``), and the vehicle gets no job for
``refuse_backoff_s``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import CommandReply, JobAssignment, VehicleCommand
from orchestrator import holders
from orchestrator.core_types import Effects
from orchestrator.fleet import ready_for_job
from orchestrator.jobs import transition
from orchestrator.requeue import hand_back

if TYPE_CHECKING:
    from orchestrator.core import Book


def assign(book: Book, eff: Effects, now_s: float) -> None:
    """Give queued jobs, in order, to ready vehicles whose board is free."""
    if book.queue_paused:
        return
    queue = book.queue()
    if not queue:
        return
    busy_boards = book.busy_boards()
    busy_vehicles = book.vehicles_with_jobs()
    for view in book.vehicles.values():
        if not queue:
            break
        vid = view.info.vehicle_id
        if vid in busy_vehicles or view.info.board_id in busy_boards:
            continue
        board_id = view.info.board_id
        if board_id in book.dirty_boards or book.sheets.busy(board_id, now_s):
            continue
        if not ready_for_job(view, now_s):
            continue
        job = next(
            (j for j in queue if book.kinds.may_take(j, vid) and holders.assignable(j, now_s)),
            None,
        )
        if job is None:
            continue
        queue.remove(job)
        job = book.put(
            eff,
            transition(
                job,
                "assigned",
                now_s,
                vehicle_id=vid,
                board_id=view.info.board_id,
                assigned_at_s=now_s,
                attempts=job.attempts + 1,
                progress=0.0,
                error=None,
                holder_hold_until_s=None,
                writing_since_s=None,
            ),
        )
        busy_boards.add(view.info.board_id)
        view.mismatch_since_s = None
        sent = JobAssignment(
            job_id=job.job_id, text=job.text, strokes=job.strokes, attempt=job.attempts
        )
        eff.commands.append((vid, VehicleCommand(command="assign", job=sent)))
        message = f"{job.label} -> {vid} (attempt {job.attempts})"
        book.event(eff, now_s, "info", "job_assigned", message, vehicle_id=vid, job_id=job.job_id)
        eff.fleet_changed = True


def answered(
    book: Book, vehicle_id: str, job_id: str, reply: CommandReply | None, now_s: float
) -> Effects:
    """The agent's answer to an assign command (None: no answer); then assign again."""
    eff = Effects()
    if reply is not None and reply.ok:
        return eff
    view = book.vehicles.get(vehicle_id)
    if view is not None:
        view.refused_until_s = now_s + book.config.refuse_backoff_s
    job = book.jobs.get(job_id)
    if job is not None and job.state == "assigned" and job.vehicle_id == vehicle_id:
        why = reply.message if reply is not None else "no answer"
        if reply is not None and reply.error is not None:
            why = reply.error.message
        hand_back(book, eff, job, now_s, f"{vehicle_id} did not take the job: {why}")
    assign(book, eff, now_s)
    return eff
