"""Giving queued jobs to vehicles (pure), and what an agent's answer to an assignment does.

Jobs go in queue order (priority, then submission) to vehicles that are ready
(``orchestrator/fleet.py:ready_for_job``), whose board is free and clean, and whose kind can
write the job (``orchestrator/kinds.py``); a job waiting for its lost vehicle goes to nobody
(``orchestrator/holders.py``). A refused or unanswered assignment puts the job back without
counting the attempt (a hand-back, ``orchestrator/requeue.py``), and the vehicle gets no job for
``refuse_backoff_s``. A ready vehicle whose battery cannot take the job it would be given and
keep the show's reserve, or that is at its reserve, is sent for a swap instead
(``orchestrator/battery_swaps.py``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.messages import CommandReply, JobAssignment, VehicleCommand
from orchestrator import battery_swaps, holders, phrase_rows, phrases
from orchestrator.core_types import Effects
from orchestrator.fleet import VehicleView, ready_for_job
from orchestrator.jobs import Job, transition
from orchestrator.requeue import hand_back

if TYPE_CHECKING:
    from orchestrator.book_protocol import BookProtocol


def assign(book: BookProtocol, eff: Effects, now_s: float) -> None:
    """Give queued jobs, in order, to ready vehicles whose board is free; a phrase's characters
    all at once to adjacent boards, or none (``orchestrator/phrases.py``)."""
    battery_swaps.check_reserves(book, eff, now_s)
    if book.queue_paused:
        return
    queue = book.queue()
    if not queue:
        return
    busy = book.vehicles_with_jobs(), book.busy_boards() | book.dirty_boards
    free = [v for v in book.vehicles.values() if _free(book, v, busy, now_s)]
    held_back: set[str] = set()
    """Boards that a phrase waiting ahead could use: no job behind it goes there."""
    singles: list[Job] = []
    for unit in phrase_rows.units(queue):
        if not phrase_rows.together(unit[0]):
            singles.append(unit[0])
            continue
        _give_singles(book, eff, singles, free, held_back, now_s)
        if any(j.state == "awaiting_approval" for j in phrases.siblings(book, unit[0])):
            continue  # a phrase goes once none of its characters awaits approval
        if not _give_phrase(book, eff, unit, free, held_back, now_s):
            held_back |= _could_use(book, unit)
    _give_singles(book, eff, singles, free, held_back, now_s)


def _free(
    book: BookProtocol, view: VehicleView, busy: tuple[set[str], set[str]], now_s: float
) -> bool:
    """Ready for a job, without one, on a board that is free, clean and has its sheet
    (``busy``: the vehicles with a job, and the boards busy or half-written)."""
    board_id = view.info.board_id
    return (
        view.info.vehicle_id not in busy[0]
        and board_id not in busy[1]
        and not book.sheets.busy(board_id, now_s)
        and ready_for_job(view, now_s)
    )


def _give_singles(
    book: BookProtocol,
    eff: Effects,
    queue: list[Job],
    free: list[VehicleView],
    held_back: set[str],
    now_s: float,
) -> None:
    """Each free vehicle (in the show's order) not on a held-back board takes the first job of
    ``queue`` it may take, or goes for a battery swap if that job would leave it short."""
    for view in list(free):
        if not queue:
            break
        vid = view.info.vehicle_id
        if view.info.board_id in held_back or view not in free:
            continue
        job = next((j for j in queue if _may_take(book, j, vid, now_s)), None)
        if job is None:
            continue
        free.remove(view)
        if (why := battery_swaps.lacks(book, view, job)) is not None:
            battery_swaps.send_for_swap(book, eff, view, why, now_s)
            continue
        queue.remove(job)
        _give(book, eff, job, view, free, now_s)


def _give_phrase(
    book: BookProtocol,
    eff: Effects,
    unit: tuple[Job, ...],
    free: list[VehicleView],
    held_back: set[str],
    now_s: float,
) -> bool:
    """Give every character of ``unit`` to free vehicles on adjacent boards in reading order
    (True), or none (False; vehicles too short of battery for their character go for a swap)."""
    open_views = [v for v in free if v.info.board_id not in held_back]

    def option(job: Job, board_id: str) -> tuple[float, str] | None:
        vid = next(
            (
                v.info.vehicle_id
                for v in open_views
                if v.info.board_id == board_id and _may_take(book, job, v.info.vehicle_id, now_s)
            ),
            None,
        )
        return None if vid is None else (0.0, vid)

    best = phrase_rows.best_window(unit, phrases.board_row(book.config), option)
    if best is None:
        return False
    seats = [(job, book.vehicles[vid]) for job, vid in best[1]]
    short = [(v, why) for job, v in seats if (why := battery_swaps.lacks(book, v, job))]
    for view, why in short:
        free.remove(view)
        battery_swaps.send_for_swap(book, eff, view, why, now_s)
    if short:
        return False
    for job, view in seats:
        _give(book, eff, job, view, free, now_s)
    return True


def _could_use(book: BookProtocol, unit: tuple[Job, ...]) -> set[str]:
    """The boards a phrase could be written on by vehicles usable now or later (present, not
    paused nor held): none when no window of them could."""
    usable = {
        vid: v.info.board_id
        for vid, v in book.vehicles.items()
        if v.alive and not v.lost and not (v.paused or v.held) and v.info.cannot_write is None
    }
    row = phrases.board_row(book.config)
    return phrase_rows.could_use(unit, row, usable, book.kinds.may_take)


def _give(
    book: BookProtocol,
    eff: Effects,
    job: Job,
    view: VehicleView,
    free: list[VehicleView],
    now_s: float,
) -> None:
    """Assign ``job`` to ``view``'s vehicle: stored, sent, logged; its board is no longer free
    for the others in ``free`` (one job per board)."""
    vid = view.info.vehicle_id
    free[:] = [v for v in free if v.info.board_id != view.info.board_id]
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
    view.mismatch_since_s = None
    sent = JobAssignment(
        job_id=job.job_id, text=job.text, strokes=job.strokes, attempt=job.attempts
    )
    eff.commands.append((vid, VehicleCommand(command="assign", job=sent)))
    message = f"{job.label} -> {vid} (attempt {job.attempts})"
    book.event(eff, now_s, "info", "job_assigned", message, vehicle_id=vid, job_id=job.job_id)
    eff.fleet_changed = True


def _may_take(book: BookProtocol, job: Job, vehicle_id: str, now_s: float) -> bool:
    """Its kind writes it, it waits for no lost vehicle, it fits the vehicle's full battery; a
    character rewritten alone goes to its own board only."""
    return (
        (not job.rewrite_alone or job.board_id == book.vehicles[vehicle_id].info.board_id)
        and book.kinds.may_take(job, vehicle_id)
        and holders.assignable(job, now_s)
        and battery_swaps.fits_full(book, vehicle_id, job)
    )


def answered(
    book: BookProtocol, vehicle_id: str, job_id: str, reply: CommandReply | None, now_s: float
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
