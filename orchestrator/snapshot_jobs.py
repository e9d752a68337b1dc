"""The jobs of a show snapshot (pure): which of the held jobs a late joiner gets, and with what."""

from __future__ import annotations

from collections.abc import Iterable, Mapping

import msgspec

from bus.messages import JobState
from orchestrator.jobs import WAITING_STATES, Job, to_state
from orchestrator.positions import Placing


def snapshot_jobs(
    jobs: Iterable[Job],
    placings: Mapping[str, Placing],
    *,
    include_final: bool,
    max_final: int,
    strokes_budget_bytes: int,
) -> list[JobState]:
    """``jobs`` in submission order, each queued one with its ``placings`` (queue position and
    ETA, ``Book.etas``). With ``include_final`` the latest ``max_final`` finished jobs are
    included too. Waiting drawn jobs carry their strokes, oldest first, while their JSON fits
    the budget."""
    held = sorted(jobs, key=lambda j: j.seq)
    finals = sorted((j.seq for j in held if j.final), reverse=True)
    oldest_final = finals[max_final - 1] if include_final and len(finals) >= max_final else 0
    budget = strokes_budget_bytes
    states = []
    for j in held:
        if j.final and not (include_final and j.seq >= oldest_final):
            continue
        waiting = j.state in WAITING_STATES and j.strokes is not None
        size = len(msgspec.json.encode(j.strokes)) if waiting and budget > 0 else 0
        with_strokes = 0 < size <= budget
        budget -= size if with_strokes else 0
        position, eta = placings.get(j.job_id, (None, None))
        states.append(to_state(j, queue_position=position, eta_s=eta, with_strokes=with_strokes))
    return states
