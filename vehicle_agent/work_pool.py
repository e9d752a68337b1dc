"""A fleet host's planning: a few worker processes shared by all its vehicles.

An agent process has a planning worker of its own (``vehicle_agent/worker_client.py``); a fleet
host of 250 vehicles cannot (a worker holds the planner, solvers and matplotlib: hundreds of MiB
each). :class:`PlanPool` keeps ``size`` workers, each able to serve any vehicle of the show
(``vehicle_agent/plan_worker.py`` makes a vehicle's setup on its first request); each vehicle's
:class:`PooledJobWork` hands its requests to the first free worker, in the order they came.
The host warms them before its vehicles join the show (:meth:`PlanPool.warm`), as an agent warms
its own. Nothing waits on the event loop: requests wait for a worker as tasks, and a prepared job
carries its planning context sealed, so any worker may measure and record a job another one
planned.
"""

from __future__ import annotations

import asyncio
import os
from collections.abc import Sequence
from typing import Any

from showfile import Show
from vehicle_agent.worker_client import IDLE_EXIT_S, ProcessJobWork, RemoteJobWork

MAX_WORKERS = 2
"""Workers of a host at most (the machine's cores are shared with the control loops)."""


def pool_size(cores: int | None = None) -> int:
    """Workers of a host: ``min(MAX_WORKERS, cores)``, at least one."""
    return max(1, min(MAX_WORKERS, cores if cores is not None else os.cpu_count() or 1))


class PlanPool:
    """``size`` planning workers serving every vehicle of a show (started on first use)."""

    def __init__(
        self, show: Show, time_scale: float, size: int, *, idle_exit_s: float = IDLE_EXIT_S
    ) -> None:
        if size < 1:
            raise ValueError("a planning pool needs at least one worker")
        self.show = show
        self.workers = [
            ProcessJobWork(
                show, None, time_scale, idle_exit_s=idle_exit_s, name=f"fleet worker {i + 1}"
            )
            for i in range(size)
        ]
        self._free: asyncio.Queue[ProcessJobWork] | None = None
        self.requests = 0
        """Requests answered or failed, for measurements."""

    def for_vehicle(self, vehicle_id: str) -> PooledJobWork:
        """The :class:`vehicle_agent.work.JobWork` of one vehicle of the host."""
        return PooledJobWork(self, vehicle_id)

    async def warm(self, vehicle_ids: Sequence[str]) -> None:
        """Start every worker and warm it for one vehicle of each kind among ``vehicle_ids``
        (:meth:`ProcessJobWork.warm`), all at once; the workers stay from now on."""
        one_of_each = {self.show.vehicle(v).kind: v for v in reversed(vehicle_ids)}
        await asyncio.gather(*(w.warm(one_of_each.values()) for w in self.workers))

    async def call(self, vehicle_id: str, request: tuple[Any, ...]) -> Any:
        """``request`` of ``vehicle_id`` answered by the first free worker."""
        free = self._queue()
        worker = await free.get()
        try:
            return await worker.call(("vehicle", vehicle_id, request))
        finally:
            self.requests += 1
            free.put_nowait(worker)

    async def close(self) -> None:
        """Stop every worker (an idle one finishes its picture first)."""
        await asyncio.gather(*(worker.close() for worker in self.workers))

    def _queue(self) -> asyncio.Queue[ProcessJobWork]:
        """The free workers (made in the running loop, on first use)."""
        if self._free is None:
            self._free = asyncio.Queue()
            for worker in self.workers:
                self._free.put_nowait(worker)
        return self._free


class PooledJobWork(RemoteJobWork):
    """One vehicle's job work done by its host's pool; closing it leaves the pool running."""

    def __init__(self, pool: PlanPool, vehicle_id: str) -> None:
        self._pool = pool
        self.vehicle_id = vehicle_id

    async def _call(self, request: tuple[Any, ...]) -> Any:
        return await self._pool.call(self.vehicle_id, request)

    async def close(self) -> None:
        return None
