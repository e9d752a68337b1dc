"""The slow work of a job, off the control loop: planning it, measuring and recording the flight.

:class:`JobWork` is what the agent service awaits; two implementations:

- :class:`ThreadJobWork`: in this process, in worker threads (tests with stand-in functions; the
  peer in ``benchmarks/bench_agent.py``). Threads share the interpreter lock with the control
  loop, so a plan's pure-Python stretches delay its ticks;
- :class:`vehicle_agent.worker_client.ProcessJobWork`: in a planning worker process of its own
  (what ``skyquill agent`` runs), so the loop keeps its period while a plan is computed.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Protocol

from bus.messages import ErrorInfo, JobAssignment, JobMetrics
from vehicle_agent.job_runner import PreparedJob
from vehicle_agent.trace import JobTrace

Prepare = Callable[[JobAssignment], PreparedJob]
"""Lays a job out on the board and plans it (may raise)."""
Measure = Callable[[PreparedJob, JobTrace], JobMetrics]
"""Metrics of a flown job."""
Archive = Callable[[PreparedJob, JobTrace, JobMetrics | None], object]
"""Keeps a record of a flown job, e.g. files on disk (may raise); returns where."""


class JobWorkError(RuntimeError):
    """A job's planning, measuring or recording failed; ``info`` says why (code, field...)."""

    def __init__(self, info: ErrorInfo) -> None:
        self.info = info
        self.code = info.code
        self.field = info.field
        self.stroke_index = info.stroke_index
        self.point_index = info.point_index
        super().__init__(info.message)


class JobWork(Protocol):
    """Planning and measuring jobs for one vehicle (every call may raise; ``close`` does not)."""

    async def prepare(self, assignment: JobAssignment) -> PreparedJob:
        """The job laid out and planned."""
        ...

    async def measure(self, prepared: PreparedJob, trace: JobTrace) -> JobMetrics:
        """Metrics of the flown job."""
        ...

    async def archive(
        self, prepared: PreparedJob, trace: JobTrace, metrics: JobMetrics | None
    ) -> object:
        """Record the flown job (None: nothing recorded); returns where."""
        ...

    async def close(self) -> None:
        """Release what the work holds (threads, a worker process); safe to call twice."""
        ...


class ThreadJobWork:
    """:class:`JobWork` done by plain functions in worker threads of this process."""

    def __init__(self, prepare: Prepare, measure: Measure, archive: Archive | None = None) -> None:
        self._prepare = prepare
        self._measure = measure
        self._archive = archive

    async def prepare(self, assignment: JobAssignment) -> PreparedJob:
        return await asyncio.to_thread(self._prepare, assignment)

    async def measure(self, prepared: PreparedJob, trace: JobTrace) -> JobMetrics:
        return await asyncio.to_thread(self._measure, prepared, trace)

    async def archive(
        self, prepared: PreparedJob, trace: JobTrace, metrics: JobMetrics | None
    ) -> object:
        if self._archive is None:
            return None
        return await asyncio.to_thread(self._archive, prepared, trace, metrics)

    async def close(self) -> None:
        return None
