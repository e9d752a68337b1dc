"""The planning worker: one process per agent that plans its jobs, measures and records them.

``python -m vehicle_agent.plan_worker PARENT_PID`` is started by
:class:`vehicle_agent.worker_client.ProcessJobWork` when its agent gets its first job. It serves
the requests of :mod:`vehicle_agent.worker_protocol` on stdin/stdout, one at a time, at a lower
CPU priority than its agent's control loop, and imports the planner, the solvers and matplotlib
so that the agent does not. It exits at the end of its stdin, on ``close``, and with its agent
(``PR_SET_PDEATHSIG``); it ignores SIGINT/SIGTERM sent to the terminal's process group (its agent
stops it, after a picture still being drawn).
"""

from __future__ import annotations

import contextlib
import ctypes
import logging
import os
import pickle
import signal
import sys
import time
from dataclasses import replace
from typing import Any, BinaryIO

from bus.rpc import error_info_from_exception
from vehicle_agent.worker_protocol import (
    FrameError,
    SealedContext,
    read_frame,
    write_frame,
)

WORKER_NICE = 5
"""How much lower the worker's CPU priority is than its agent's (the loop flies; plans wait)."""
PICTURE_WAIT_S = 3.0
"""On ``close``, how long in [s] the worker waits for a job's report.png still being drawn."""
PR_SET_PDEATHSIG = 1

log = logging.getLogger("vehicle_agent.plan_worker")


class Worker:
    """The requests' handlers (imports the heavy modules on ``init``)."""

    def __init__(self) -> None:
        self._setup: Any = None
        self._pictures: Any = None

    def handle(self, request: tuple[Any, ...]) -> Any:
        """The value answering ``request`` (raises what the work raises)."""
        name = request[0]
        if name == "init":
            return self._init(*request[1:])
        if self._setup is None:
            raise RuntimeError("the planning worker was not told its vehicle")
        if name == "prepare":
            return self._prepare(request[1])
        from vehicle_agent import jobs

        prepared = _opened(request[1])
        if name == "measure":
            return jobs.job_metrics(self._setup, prepared, request[2])
        if name == "archive":
            where = jobs.archive_job(self._setup, self._pictures, prepared, *request[2:])
            return str(where)
        raise ValueError(f"the planning worker has no request {name!r}")

    def close(self) -> None:
        """Wait for a picture still being drawn."""
        if self._pictures is not None:
            self._pictures.wait(PICTURE_WAIT_S)

    def _init(self, show: Any, vehicle_id: str, time_scale: float) -> None:
        from vehicle_agent.job_picture import PictureWorker
        from vehicle_agent.setup import vehicle_setup

        self._setup = vehicle_setup(show, vehicle_id, time_scale=time_scale)
        self._pictures = PictureWorker(vehicle_id)

    def _prepare(self, assignment: Any) -> Any:
        from vehicle_agent.jobs import prepare_job

        prepared = prepare_job(self._setup, assignment)
        sealed = SealedContext(pickle.dumps(prepared.context, protocol=pickle.HIGHEST_PROTOCOL))
        return replace(prepared, context=sealed)


def _opened(prepared: Any) -> Any:
    """A prepared job with its sealed context opened again."""
    context = prepared.context
    if isinstance(context, SealedContext):
        return replace(prepared, context=pickle.loads(context.blob))
    return prepared


def serve(requests: BinaryIO, replies: BinaryIO, worker: Worker) -> None:
    """Answer requests until ``close`` or the end of ``requests``."""
    while True:
        try:
            request = read_frame(requests)
        except FrameError:
            return
        if not isinstance(request, tuple) or not request:
            raise ValueError(f"not a request: {type(request).__name__}")
        if request[0] == "close":
            worker.close()
            write_frame(replies, ("ok", None, 0.0))
            return
        started_cpu_s = time.process_time()
        try:
            value = worker.handle(request)
        except Exception as exc:
            log.info("%s failed: %s", request[0], exc)
            write_frame(replies, ("error", error_info_from_exception(exc)))
        else:
            write_frame(replies, ("ok", value, time.process_time() - started_cpu_s))


def _die_with(parent_pid: int) -> None:
    """Be killed when the agent dies, whatever kills it; exit now if it is gone already."""
    with contextlib.suppress(OSError):
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent_pid:
        os._exit(0)


def main(argv: list[str]) -> int:
    parent_pid = int(argv[0])
    _die_with(parent_pid)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_IGN)
    os.nice(WORKER_NICE)
    logging.basicConfig(
        level=logging.WARNING,
        format="%(asctime)s plan worker %(levelname)s %(message)s",
        stream=sys.stderr,
    )
    replies = os.fdopen(os.dup(sys.stdout.fileno()), "wb")
    os.dup2(sys.stderr.fileno(), sys.stdout.fileno())  # a stray print must not break a frame
    serve(sys.stdin.buffer, replies, Worker())
    replies.close()
    logging.shutdown()
    sys.stderr.flush()
    os._exit(0)  # skip the teardown of the heavy modules: the agent waits for this exit


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
