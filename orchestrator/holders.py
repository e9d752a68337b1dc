"""A job taken back from a lost vehicle waits for that vehicle (pure): nobody writes it twice.

Losing a vehicle (its token gone, or silent, for ``lost_after_s``: a router restart, a Wi-Fi
drop, a crash), or restarting the orchestrator, does not say whether the vehicle is still writing
its job, nor whether it has finished it; nor does the operator's ``land`` or ``estop`` of a vehicle
whose brush may have gone down (its writing may have ended a moment before, its result on its
way: given to the next vehicle at once, the character was written twice in full,
``tests/test_write_fence.py``). So the job goes back to the queue for its last holder alone and
its board is left as it is:

- back with the job (its status or a report names it: writing on, or written and its result on
  its way), the vehicle has it again (``job_reclaimed``), or its result is taken;
- back without it (it gave the job up, or its agent restarted before the end), the job is free
  at once, for another vehicle first (that one takes no job for ``refuse_backoff_s``), and a board
  it may have begun is marked half-written;
- not back: a job it cannot have begun (no *ready* report stored: its brush never went down) is
  free after ``lost_job_hold_s``. A job it may have begun waits for its word, however long: it may
  have written it in full and not been able to say so. After the write fence
  (``bus/fence.py``: it can no longer be inking) plus ``lost_job_hold_s`` (:func:`hold_until_s`),
  an alert (``job_waits``) tells the operator; a fresh sheet on that vehicle's board
  (``fresh_sheet``: the operator has looked, and nothing of the job is left there) frees the job,
  and what the old holder says of it afterwards is refused (``not_assigned``).

Why no character is written twice in full, under any interleaving: another vehicle is given a
job only when it is queued and nobody waits for it. A job's last holder writes it in full only
after a ready report the orchestrator stored (``Job.writing_since_s``) before acknowledging it.
From then on the job waits for that holder whenever it is taken back, until (a) the holder
says it has the job (reclaimed, or its result taken: then it is the holder's alone again), or
(b) the holder speaks without naming it; its agent names a job from its assignment until the
orchestrator has answered its result, across restarts too (``vehicle_agent/results.py``), so (b)
means it did not write it in full; or (c) the operator replaced the sheet, and a result the holder
sends after that is refused: the character is not on any board. A job with no stored ready report
cannot have been inked at all. ``tests/test_write_fence.py`` checks this against a model.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.fence import unheard_writing_s
from orchestrator import phrase_rows
from orchestrator.core_types import CoreConfig, Effects
from orchestrator.jobs import Job, transition, update

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def writing_fence_s(config: CoreConfig, job: Job) -> float | None:
    """Unix time [s] after which the job's last holder cannot be writing it any more, if it began
    writing it (None: it had not, as far as this orchestrator heard)."""
    if job.writing_since_s is None or job.planned_duration_s is None:
        return None
    unheard_s = unheard_writing_s(
        job.planned_duration_s, config.eta.time_scale, config.lost_after_s
    )
    return job.writing_since_s + unheard_s


def hold_until_s(config: CoreConfig, job: Job, now_s: float) -> float:
    """Until when a job taken back from its lost vehicle waits for it, Unix time [s]."""
    fence = writing_fence_s(config, job)
    return max(now_s, fence or now_s) + config.lost_job_hold_s


def left_half_written(book: BookProtocol, eff: Effects, job: Job, now_s: float) -> None:
    """``job``'s board has a half-written character on it: no job there until a fresh sheet."""
    if job.board_id is None:
        return
    book.dirty_boards.add(job.board_id)
    eff.settings_changed = True
    message = f"{job.board_id} half-written by {job.label}: fresh sheet needed"
    book.event(
        eff, now_s, "alert", "board_dirty", message, vehicle_id=job.vehicle_id, job_id=job.job_id
    )


def waits_for(job: Job, now_s: float) -> str | None:
    """The vehicle a queued job still waits for (None: any vehicle may take it): one that may
    have begun it, until it is heard; one that cannot have, until ``holder_hold_until_s``."""
    until = job.holder_hold_until_s
    if job.state != "queued" or until is None:
        return None
    if job.writing_since_s is None and now_s >= until:
        return None
    return job.vehicle_id


def overdue(job: Job, now_s: float) -> bool:
    """Whether ``job`` waits for a holder that may have written it and is past its hold: only
    the holder's word or a fresh sheet on its board frees it now."""
    until = job.holder_hold_until_s
    return waits_for(job, now_s) is not None and until is not None and now_s >= until


def tell_overdue(book: BookProtocol, eff: Effects, now_s: float) -> None:
    """Alert once for each job that has begun waiting for its holder beyond its hold (and
    forget the alerted jobs that wait no more)."""
    book.told_overdue &= {j.job_id for v in book.vehicles if (j := book.awaited_by(v))}
    for vehicle_id in book.vehicles:
        job = book.awaited_by(vehicle_id)
        if job is None or not overdue(job, now_s) or job.job_id in book.told_overdue:
            continue
        book.told_overdue.add(job.job_id)
        board = job.board_id or "its board"
        message = (
            f"{job.label} waits for {vehicle_id}, which may have written it: nobody else writes"
            f" it until {vehicle_id} says how it ended. If {vehicle_id} cannot come back, put a"
            f" fresh sheet on {board}: then another vehicle writes it"
        )
        book.event(
            eff, now_s, "alert", "job_waits", message, vehicle_id=vehicle_id, job_id=job.job_id
        )


def overdue_boards(book: BookProtocol) -> set[str]:
    """Boards of the vehicles whose job has been alerted as overdue and still waits for them."""
    return {
        view.info.board_id
        for vid, view in book.vehicles.items()
        if (job := book.awaited_by(vid)) is not None and job.job_id in book.told_overdue
    }


def free_on_fresh_sheet(
    book: BookProtocol, eff: Effects, board_id: str, now_s: float
) -> Job | None:
    """The operator put a fresh sheet on ``board_id``: an overdue job waiting for that board's
    vehicle is free for anyone, its old holder no longer heard about it; returns it."""
    for view in book.vehicles.values():
        job = book.awaited_by(view.info.vehicle_id)
        if view.info.board_id != board_id or job is None or not overdue(job, now_s):
            continue
        holder = job.vehicle_id
        book.put(
            eff,
            update(job, now_s, vehicle_id=None, holder_hold_until_s=None, writing_since_s=None),
        )
        message = f"{job.label}: fresh sheet on {board_id}; another vehicle writes it, not {holder}"
        book.event(
            eff, now_s, "warning", "job_released", message, vehicle_id=holder, job_id=job.job_id
        )
        return job
    return None


def assignable(job: Job, now_s: float) -> bool:
    """Whether ``job`` may be given to a vehicle now: not while it waits for its last holder
    (who gets it back only by naming it; back without it, it frees it)."""
    return waits_for(job, now_s) is None


def heard_without(
    book: BookProtocol, eff: Effects, vehicle_id: str, job_id: str | None, now_s: float
) -> None:
    """The vehicle spoke, naming ``job_id``: a job waiting for it that it does not name is free."""
    job = book.awaited_by(vehicle_id)
    if job is None or job.job_id == job_id or waits_for(job, now_s) is None:
        return
    if job.writing_since_s is not None:
        left_half_written(book, eff, job, now_s)
    book.put(eff, update(job, now_s, holder_hold_until_s=None, writing_since_s=None, progress=0.0))
    view = book.vehicles[vehicle_id]  # it crashed or gave the job up: another vehicle first
    view.refused_until_s = max(view.refused_until_s, now_s + book.config.refuse_backoff_s)
    message = f"{job.label}: {vehicle_id} is back without it; the next vehicle takes it"
    book.event(
        eff, now_s, "info", "job_released", message, vehicle_id=vehicle_id, job_id=job.job_id
    )


def reclaim(book: BookProtocol, eff: Effects, job: Job, vehicle_id: str, now_s: float) -> bool:
    """``vehicle_id`` named ``job`` (a status or a report): if the job is back in the queue with
    it as the last holder and nobody else has it, the vehicle has it again; True if so."""
    view = book.vehicles.get(vehicle_id)
    if job.state != "queued" or job.vehicle_id != vehicle_id or view is None:
        return False  # only the last holder, only while nobody else has it
    if not view.alive or view.held or book.active_job_of(vehicle_id) is not None:
        return False  # held: the operator took the job away (sent before the agent knew)
    if view.info.board_id in book.busy_boards() or phrase_rows.together(job):
        return False  # a character of a phrase not begun goes out again with its phrase
    reclaimed = transition(
        job,
        "assigned",
        now_s,
        board_id=view.info.board_id,
        assigned_at_s=now_s,
        error=None,
        holder_hold_until_s=None,
    )
    book.put(eff, reclaimed)
    message = f"{vehicle_id} still has {job.label}"
    book.event(
        eff, now_s, "info", "job_reclaimed", message, vehicle_id=vehicle_id, job_id=job.job_id
    )
    eff.fleet_changed = True
    return True
