"""The agent's end of its planning worker (:mod:`vehicle_agent.plan_worker`): a :class:`JobWork`
whose plans, metrics and records are made in another process, outside the control loop's
interpreter.

An agent starts its worker and warms it (:meth:`ProcessJobWork.warm`) before its vehicle joins the
show: started at the first job instead, the worker's imports (1.4 s CPU, 19.5 s wall at load 25)
delayed every first job of a show and put every queued job's ETA early by the same 29-35 s
(issue 35). A warmed worker stays for the agent's life (stopped when idle, the next job would be
cold again). One never warmed is started at the first request and stopped after ``idle_exit_s``
without requests (tests, benchmarks). Requests go one at a time.
A worker that dies or answers nonsense fails the request with a clear :class:`JobWorkError`
(code ``worker_failed``) and is started afresh by the next one. ``close`` stops it: gently when it
is idle (it finishes a picture first), at once when it is busy; no process is left behind.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import sys
from collections.abc import Iterable
from typing import Any

from bus.messages import ErrorInfo, JobAssignment, JobMetrics
from showfile import Show
from vehicle_agent.job_runner import PreparedJob
from vehicle_agent.trace import JobTrace
from vehicle_agent.work import JobWorkError
from vehicle_agent.worker_protocol import FrameError, body_length, frame, unframe

log = logging.getLogger(__name__)

IDLE_EXIT_S = 120.0
"""Wall time in [s] without requests after which a worker never warmed is stopped (between jobs
of a running show it is kept; an idle one frees its memory)."""
CLOSE_WAIT_S = 25.0
"""How long in [s] ``close`` waits for an idle worker to exit (it may be drawing a picture: the
worker's own wait, ``plan_worker.PICTURE_WAIT_S``, and its exit)."""


class RemoteJobWork:
    """:class:`vehicle_agent.work.JobWork` answered by a planning worker through ``_call``
    (checks the type of each answer; a subclass says which worker answers)."""

    vehicle_id: str

    async def prepare(self, assignment: JobAssignment) -> PreparedJob:
        prepared = await self._call(("prepare", assignment))
        if not isinstance(prepared, PreparedJob):
            raise worker_failed(self.vehicle_id, f"answered prepare with a {_name(prepared)}")
        return prepared

    async def measure(self, prepared: PreparedJob, trace: JobTrace) -> JobMetrics:
        metrics = await self._call(("measure", prepared, trace))
        if not isinstance(metrics, JobMetrics):
            raise worker_failed(self.vehicle_id, f"answered measure with a {_name(metrics)}")
        return metrics

    async def archive(
        self, prepared: PreparedJob, trace: JobTrace, metrics: JobMetrics | None
    ) -> object:
        return await self._call(("archive", prepared, trace, metrics))

    async def _call(self, request: tuple[Any, ...]) -> Any:
        raise NotImplementedError


class ProcessJobWork(RemoteJobWork):
    """A planning worker process of this agent's own (``vehicle_id``), or, with ``vehicle_id``
    None, one serving any vehicle of ``show`` through :meth:`call` (a fleet host's pool)."""

    def __init__(
        self,
        show: Show,
        vehicle_id: str | None,
        time_scale: float,
        *,
        idle_exit_s: float | None = IDLE_EXIT_S,
        name: str | None = None,
    ) -> None:
        """``idle_exit_s``: stop the worker after so long without requests (None: never)."""
        self._init = ("init", show, vehicle_id, time_scale)
        self.vehicle_id = name or vehicle_id or "the fleet host"
        """Who the worker works for (log lines, errors)."""
        self.idle_exit_s = idle_exit_s
        self._process: asyncio.subprocess.Process | None = None
        self._lock = asyncio.Lock()
        self._busy = False
        self._idle_timer: asyncio.TimerHandle | None = None
        self._closing: asyncio.Task[None] | None = None
        self.last_cpu_s = 0.0
        """The worker's CPU time in [s] of the last request answered."""
        self.starts = 0
        """How many worker processes were started."""

    @property
    def pid(self) -> int | None:
        """The running worker's process id (None: none runs)."""
        process = self._process
        return None if process is None or process.returncode is not None else process.pid

    async def warm(self, vehicle_ids: Iterable[str] = ()) -> float | None:
        """Start the worker and plan a small character in it, as a job is planned; the worker
        stays from now on. ``vehicle_ids``: the vehicles a worker serving any vehicle of the
        show (a fleet host's) is warmed for (one of each kind is enough). Returns the
        warm-up's CPU time in [s] (start-up not counted), or None when it failed (logged: the
        first job starts a worker afresh and reports what fails then)."""
        self.idle_exit_s = None
        requests: list[tuple[Any, ...]] = [("vehicle", v, ("warm",)) for v in vehicle_ids]
        cpu_s = 0.0
        try:
            for request in requests or [("warm",)]:
                await self._call(request)
                cpu_s += self.last_cpu_s
        except JobWorkError as exc:
            log.warning("%s: the planning worker did not warm up: %s", self.vehicle_id, exc)
            return None
        return cpu_s

    async def call(self, request: tuple[Any, ...]) -> Any:
        """The worker's answer to ``request`` (JobWorkError when it failed or died)."""
        return await self._call(request)

    async def close(self) -> None:
        """Stop the worker: let an idle one finish its picture, kill a busy one."""
        if self._idle_timer is not None:
            self._idle_timer.cancel()
        process, self._process = self._process, None
        if process is None or process.returncode is not None:
            return
        if not self._busy and process.stdin is not None:
            with contextlib.suppress(OSError):
                process.stdin.write(frame(("close",)))
                process.stdin.close()
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(process.wait(), CLOSE_WAIT_S)
        if process.returncode is None:
            process.kill()
            await process.wait()

    # --- the pipe ------------------------------------------------------------------------------
    async def _call(self, request: tuple[Any, ...]) -> Any:
        async with self._lock:
            if self._idle_timer is not None:
                self._idle_timer.cancel()
            self._busy = True
            try:
                process = await self._running()
                reply = await self._exchange(process, request)
            finally:
                self._busy = False
                if self.idle_exit_s is not None:
                    self._idle_timer = asyncio.get_running_loop().call_later(
                        self.idle_exit_s, self._idle_exit
                    )
        return self._value(reply, request[0])

    async def _running(self) -> asyncio.subprocess.Process:
        process = self._process
        if process is not None and process.returncode is None:
            return process
        process = await asyncio.create_subprocess_exec(
            sys.executable,
            "-m",
            "vehicle_agent.plan_worker",
            str(os.getpid()),
            stdin=asyncio.subprocess.PIPE,
            stdout=asyncio.subprocess.PIPE,
        )
        self._process = process
        self.starts += 1
        log.info("%s: planning worker %d started", self.vehicle_id, process.pid)
        self._value(await self._exchange(process, self._init), "init")
        return process

    async def _exchange(self, process: asyncio.subprocess.Process, request: object) -> Any:
        assert process.stdin is not None and process.stdout is not None
        try:
            process.stdin.write(frame(request))
            await process.stdin.drain()
            length = body_length(await process.stdout.readexactly(4))
            return unframe(await process.stdout.readexactly(length))
        except asyncio.CancelledError:
            # An answer nobody waits for (its agent stops): stopping waited for a plan to be
            # made or the worker to start (8 s, then SIGKILL, issue 34), and the answer would
            # put the pipe out of step. A job's record being written is let finish (close
            # waits for it).
            if request_name(request) != "archive" and process.returncode is None:
                process.kill()
                self._process = None
            raise
        except (OSError, FrameError, asyncio.IncompleteReadError) as exc:
            if process.returncode is None:
                process.kill()
            code = await process.wait()
            self._process = None
            raise self._failed(f"exited (code {code}) while answering: {exc}") from exc

    def _value(self, reply: Any, request_name: str) -> Any:
        if isinstance(reply, tuple) and len(reply) == 3 and reply[0] == "ok":
            self.last_cpu_s = float(reply[2])
            return reply[1]
        if isinstance(reply, tuple) and len(reply) == 2 and isinstance(reply[1], ErrorInfo):
            raise JobWorkError(reply[1])
        raise self._failed(f"answered {request_name} with {type(reply).__name__}")

    def _failed(self, what: str) -> JobWorkError:
        return worker_failed(self.vehicle_id, what)

    def _idle_exit(self) -> None:
        self._idle_timer = None
        if not self._busy and self._process is not None:
            log.info("%s: planning worker idle; stopping it", self.vehicle_id)
            self._closing = asyncio.get_running_loop().create_task(self.close())


def request_name(request: object) -> str | None:
    """The name of a request to the worker (``prepare``, ``measure``...)."""
    return request[0] if isinstance(request, tuple) and request else None


def worker_failed(vehicle_id: str, what: str) -> JobWorkError:
    """The error of a request the planning worker of ``vehicle_id`` could not answer."""
    message = f"the planning worker of {vehicle_id} {what}"
    return JobWorkError(ErrorInfo(code="worker_failed", message=message))


def _name(value: object) -> str:
    return type(value).__name__
