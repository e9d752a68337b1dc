"""Phrases in the queue and on the row of boards (pure, on jobs alone): which jobs go together,
and which window of adjacent boards a phrase may take (``orchestrator/phrases.py`` says why).

Below the fleet's ETAs (``orchestrator/fleet.py``) and the assignment
(``orchestrator/assignment.py``), which both place phrases with these.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from orchestrator.jobs import Job


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
    return [tuple(sorted(g, key=phrase_index)) for g in out]


def phrase_index(job: Job) -> int:
    """The character's place in its phrase, from the left (0: a job of its own)."""
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
