"""A job taken back from a lost vehicle waits for that vehicle a while (pure).

Losing a vehicle (its token gone, or silent, for ``lost_after_s``: a router restart, a Wi-Fi
drop, a crash), or restarting the orchestrator, does not say whether the vehicle is still writing
its job. Its lease (``vehicle_agent/lease.py``) lets it write unheard until the write fence
(``bus/fence.py``): only after a *ready* report this orchestrator stored and acknowledged, and
then for the planned writing time (with room for a slow host) after the latest such report. So
the job goes back to the queue for its last holder alone, for ``CoreConfig.lost_job_hold_s`` past
the later of now and that fence (:func:`hold_until_s`), and its board is left as it is: back with
the job (its status or a report names it), the vehicle has it again (``job_reclaimed``) and
writes on; back without it (it gave the job up, or its agent restarted), the job is free at once,
for another vehicle first (that one takes no job for ``refuse_backoff_s``), and a board it may
have begun (a ready report was stored) is marked half-written then. After the hold anyone may
take it, with a warning: the old holder can no longer be writing it, but if it had finished it
and could not say so since, the character is written twice.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from bus.fence import unheard_writing_s
from orchestrator.core_types import CoreConfig, Effects
from orchestrator.jobs import Job, transition, update

if TYPE_CHECKING:
    from orchestrator.core import Book


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


def left_half_written(book: Book, eff: Effects, job: Job, now_s: float) -> None:
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
    """The vehicle a queued job still waits for (None: any vehicle may take it)."""
    until = job.holder_hold_until_s
    if job.state != "queued" or until is None or now_s >= until:
        return None
    return job.vehicle_id


def assignable(job: Job, now_s: float) -> bool:
    """Whether ``job`` may be given to a vehicle now: not while it waits for its last holder
    (who gets it back only by naming it; back without it, it frees it)."""
    return waits_for(job, now_s) is None


def warn_if_taken_over(book: Book, eff: Effects, job: Job, vehicle_id: str, now_s: float) -> None:
    """``job``, held for a lost vehicle until lately, now goes to ``vehicle_id``: say so."""
    holder = job.vehicle_id
    if job.holder_hold_until_s is None or holder in (None, vehicle_id):
        return
    if job.writing_since_s is not None:
        left_half_written(book, eff, job, now_s)
    message = (
        f"{job.label}: {holder} did not come back in time;"
        f" {vehicle_id} writes it (twice, if {holder} had finished it)"
    )
    book.event(
        eff, now_s, "warning", "job_taken_over", message, vehicle_id=vehicle_id, job_id=job.job_id
    )


def heard_without(
    book: Book, eff: Effects, vehicle_id: str, job_id: str | None, now_s: float
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


def reclaim(book: Book, eff: Effects, job: Job, vehicle_id: str, now_s: float) -> bool:
    """``vehicle_id`` named ``job`` (a status or a report): if the job is back in the queue with
    it as the last holder and nobody else has it, the vehicle has it again; True if so."""
    view = book.vehicles.get(vehicle_id)
    if job.state != "queued" or job.vehicle_id != vehicle_id or view is None:
        return False  # only the last holder, only while nobody else has it
    if not view.alive or view.held or book.active_job_of(vehicle_id) is not None:
        return False  # held: the operator took the job away (sent before the agent knew)
    if view.info.board_id in book.busy_boards():
        return False
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
