"""The ink picture of a finished job (pure): kept apart from the job, sent only where asked.

A vehicle's ``done`` report carries :class:`bus.messages.WrittenInk` inside its metrics (a few
kB). The orchestrator keeps it out of the job it holds in memory and out of ``fleet``: it is
stored in its own column, sent once on the job's ``jobs/<id>`` publication, and attached to the
newest finished jobs of a ``snapshot`` reply while they fit a byte budget.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping

import msgspec

from bus.codec import encode
from bus.messages import JobMetrics, JobState, ShowSnapshot, WrittenInk


def split_written(metrics: JobMetrics | None) -> tuple[JobMetrics | None, WrittenInk | None]:
    """``metrics`` without its ink picture, and the picture (None when there is none)."""
    if metrics is None or metrics.written is None:
        return metrics, None
    return msgspec.structs.replace(metrics, written=None), metrics.written


def with_written(state: JobState, written: WrittenInk | None) -> JobState:
    """``state`` whose metrics carry ``written`` (unchanged without metrics or picture)."""
    if written is None or state.metrics is None:
        return state
    return msgspec.structs.replace(
        state, metrics=msgspec.structs.replace(state.metrics, written=written)
    )


def attach_written(
    snapshot: ShowSnapshot,
    lookup: Callable[[Iterable[str]], Mapping[str, WrittenInk]],
    budget_bytes: int,
) -> ShowSnapshot:
    """``snapshot`` with the ink pictures of its newest done jobs (and failed ones: written out
    of their bounds), newest first, while their JSON fits ``budget_bytes``; ``lookup``: job
    ids -> stored pictures (e.g. the job store)."""
    done = [j.job_id for j in reversed(snapshot.jobs) if j.state in ("done", "failed")]
    if not done or budget_bytes <= 0:
        return snapshot
    found = lookup(done)
    chosen: dict[str, WrittenInk] = {}
    for job_id in done:
        ink = found.get(job_id)
        if ink is None:
            continue
        size = len(encode(ink))
        if size > budget_bytes:
            break
        budget_bytes -= size
        chosen[job_id] = ink
    if not chosen:
        return snapshot
    jobs = [with_written(j, chosen.get(j.job_id)) for j in snapshot.jobs]
    return msgspec.structs.replace(snapshot, jobs=jobs)
