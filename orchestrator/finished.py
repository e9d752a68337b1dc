"""Bookkeeping of finished jobs (pure): exact counts per state, and a bounded memory of them.

A show running for days finishes thousands of jobs. The Book holds only the latest
``max_jobs`` to finish (as many as a ``snapshot`` reply lists); older ones are only in the
database (``orchestrator/store.py``), so memory and the scans every decision makes stay bounded:
keeping them all grew the orchestrator by about 6 KiB per job. Counts per state are kept apart
from that list, changed as jobs change, so ``status`` and the console count every job ever
stored, not the ones held.
"""

from __future__ import annotations

from collections import Counter, deque
from collections.abc import Iterable, Mapping

from orchestrator.jobs import Job

MAX_FINAL_JOBS = 500
"""Finished jobs kept in memory, the latest to finish: as many as a ``snapshot`` reply lists."""


class FinishedJobs:
    """Jobs per state, and the order in which the held finished jobs finished."""

    def __init__(
        self,
        jobs: Iterable[Job],
        counts: Mapping[str, int] | None = None,
        max_jobs: int = MAX_FINAL_JOBS,
    ) -> None:
        """``jobs``: those held (as restored); ``counts``: jobs per state in the database
        (default: counted from ``jobs``)."""
        held = list(jobs)
        self.max_jobs = max_jobs
        """Finished jobs held at most."""
        self.counts: Counter[str] = Counter(
            counts if counts is not None else (j.state for j in held)
        )
        """Jobs per state, every job counted."""
        self.order: deque[str] = deque(
            j.job_id for j in sorted(held, key=lambda j: (j.updated_at_s, j.seq)) if j.final
        )
        """Ids of the held finished jobs, in the order they finished (oldest first)."""

    def changed(self, previous: Job | None, job: Job) -> list[str]:
        """Count ``job`` (the new version of ``previous``, None: a new job); the ids of the
        oldest finished jobs to forget now."""
        if previous is not None:
            self.counts[previous.state] -= 1
        self.counts[job.state] += 1
        if job.final and (previous is None or not previous.final):
            self.order.append(job.job_id)
        return self.overflow()

    def overflow(self) -> list[str]:
        """The ids of finished jobs held beyond ``max_jobs``, oldest first (no longer held)."""
        return [self.order.popleft() for _ in range(len(self.order) - self.max_jobs)]
