"""Queue positions and ETAs as last published, so that every change is published again (pure).

A queued job's ``queue_position`` and ``eta_s`` change when another job is submitted, assigned,
cancelled, reprioritised or requeued, or when a vehicle comes or goes. The protocol publishes a
JobState "on every change", so after each decision the :class:`~orchestrator.core.Book` compares
the queue with what was last published (:func:`announce`) and lists the jobs to publish again.

The ETA is compared as an expected start time (now + ETA): one that only counts down as time
passes is not a change; one that moves by more than a tolerance is.
"""

from __future__ import annotations

from collections.abc import Mapping, Set

Placing = tuple[int, float | None]
"""A queued job's queue position (1 = next) and ETA in [s] (None: unknown)."""
Announced = dict[str, tuple[int, float | None]]
"""Per queued job: the position and expected start (Unix time [s], None: unknown) last published."""


def _start(placing: Placing, now_s: float) -> tuple[int, float | None]:
    position, eta_s = placing
    return position, None if eta_s is None else now_s + eta_s


def _same(old: tuple[int, float | None], new: tuple[int, float | None], tolerance_s: float) -> bool:
    if old[0] != new[0]:
        return False
    if old[1] is None or new[1] is None:
        return old[1] is new[1]
    return abs(old[1] - new[1]) <= tolerance_s


def announce(
    announced: Announced,
    current: Mapping[str, Placing],
    published: Set[str],
    now_s: float,
    tolerance_s: float,
) -> set[str]:
    """Queued jobs to publish again because their placing changed; updates ``announced``.

    ``current``: every queued job's placing now (``Book.etas``); ``published``: jobs the decision
    publishes anyway (they carry their new placing). Jobs no longer queued are forgotten.
    """
    moved: set[str] = set()
    for job_id in [j for j in announced if j not in current]:
        del announced[job_id]
    for job_id, placing in current.items():
        new = _start(placing, now_s)
        old = announced.get(job_id)
        if job_id in published:
            announced[job_id] = new
        elif old is None or not _same(old, new, tolerance_s):
            announced[job_id] = new
            moved.add(job_id)
    return moved
