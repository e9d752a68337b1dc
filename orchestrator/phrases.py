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
- **ETAs** (``orchestrator/fleet.py``): the characters of a phrase start at the earliest time a
  window of adjacent boards has a vehicle free for each, and the boards it could use take no job
  behind it before then.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import TYPE_CHECKING

from orchestrator.jobs import Job

if TYPE_CHECKING:
    from orchestrator.core import Book
    from orchestrator.core_types import CoreConfig


def board_row(config: CoreConfig) -> list[str]:
    """The row of boards left to right: the show's boards in its order, or, when none is
    declared apart, the boards in the order the vehicles name them."""
    declared = [board_id for board_id, _ in config.boards]
    return list(dict.fromkeys(declared or (v.board_id for v in config.vehicles)))


def together(job: Job) -> bool:
    """Whether ``job`` is dispatched and started with its phrase (not a character rewritten
    alone, not a job of its own)."""
    return job.phrase is not None and not job.rewrite_alone


def units(queue: Sequence[Job]) -> list[tuple[Job, ...]]:
    """The queue as it is dispatched: each job on its own, and the queued characters of each
    phrase together, in reading order, at the place of its first in the queue."""
    groups: dict[str, list[Job]] = {}
    out: list[list[Job]] = []
    for job in queue:
        if job.phrase is None or not together(job):
            out.append([job])
            continue
        group = groups.get(job.phrase.phrase_id)
        if group is None:
            group = groups[job.phrase.phrase_id] = []
            out.append(group)
        group.append(job)
    return [tuple(sorted(g, key=_index)) for g in out]


def _index(job: Job) -> int:
    return job.phrase.index if job.phrase is not None else 0


def windows(row: Sequence[str], n: int) -> list[Sequence[str]]:
    """Every run of ``n`` adjacent boards of ``row``, from the left (none when ``n`` is 0)."""
    return [row[start : start + n] for start in range(len(row) - n + 1)] if n > 0 else []


def best_window(
    members: Sequence[Job],
    row: Sequence[str],
    option: Callable[[Job, str], tuple[float, str] | None],
) -> tuple[float, list[tuple[Job, str]]] | None:
    """The window of ``len(members)`` adjacent boards of ``row`` whose latest seat is the
    earliest (leftmost on ties), and its seats (job, vehicle id) in reading order; None when
    no window has a seat for each. ``option(job, board)``: (cost, vehicle) of the best vehicle
    on ``board`` for ``job``, or None."""
    best: tuple[float, list[tuple[Job, str]]] | None = None
    for window in windows(row, len(members)):
        picks = [option(job, board) for job, board in zip(members, window, strict=True)]
        chosen = [p for p in picks if p is not None]
        if len(chosen) < len(members):
            continue
        cost = max(c for c, _ in chosen)
        if best is None or cost < best[0]:
            best = (cost, [(job, vid) for job, (_, vid) in zip(members, chosen, strict=True)])
    return best


def could_use(
    unit: Sequence[Job],
    row: Sequence[str],
    usable_boards: Mapping[str, str],
    may_take: Callable[[Job, str], bool] | None,
) -> set[str]:
    """The boards of every window that the vehicles of ``usable_boards`` (vehicle id -> board)
    could write the phrase ``unit`` on (``may_take(job, vehicle)``, default: any); empty when
    none could."""
    boards: set[str] = set()
    for window in windows(row, len(unit)):
        if all(
            any(
                b == board and (may_take is None or may_take(j, v))
                for v, b in usable_boards.items()
            )
            for j, board in zip(unit, window, strict=True)
        ):
            boards.update(window)
    return boards


def siblings(book: Book, job: Job) -> list[Job]:
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


def not_begun(book: Book, job: Job) -> bool:
    """Whether ``job`` is a character of a phrase of which no character has begun: taken back,
    it takes the others back with it."""
    return together(job) and not began(job) and not any(began(j) for j in siblings(book, job))


def may_write(book: Book, job: Job, now_s: float) -> bool:
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


def waiting_for(book: Book, job: Job) -> str:
    """Why a *ready* report of ``job`` is not acknowledged yet, in one line."""
    late = [
        j.label for j in siblings(book, job) if not j.final and j.job_id not in book.phrase_ready
    ]
    return f"{job.label} waits for {' '.join(late) or 'its phrase'} to start together"
