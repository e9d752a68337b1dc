"""The planning worker: a process that plans an agent's jobs, measures and records them (one per
agent process; a fleet host shares a few among all its vehicles, ``vehicle_agent/work_pool.py``).

``python -m vehicle_agent.plan_worker PARENT_PID`` is started by
:class:`vehicle_agent.worker_client.ProcessJobWork`: an agent starts and warms it (``warm``: a
one-stroke character planned, every module of a plan imported) before its vehicle joins the show,
so its first job plans as fast as any other. It serves the requests of
:mod:`vehicle_agent.worker_protocol` on stdin/stdout, one at a time, below the control loop
(:func:`main`), and imports the planner and the solvers so that the agent does not; it draws no
picture itself (a short-lived process draws each batch, ``vehicle_agent/picture_process.py``:
matplotlib stays out). After each job's record (``archive``) it collects its garbage and gives
the freed heap back to the system (a worker kept for the show holds what it reuses: modules and
caches, not what past jobs left). ``("loaded", prefixes)`` answers which modules it has
imported, for the tests that keep what it loads in check. It exits at the end of its stdin, on
``close``, and with its agent (``PR_SET_PDEATHSIG``); it ignores SIGINT/SIGTERM sent to the
terminal's process group (its agent stops it, after a picture still being drawn).
"""

from __future__ import annotations

import contextlib
import ctypes
import gc
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

PICTURE_WAIT_S = 20.0
"""On ``close``, how long in [s] the worker waits for a job's report.png still being drawn.
A picture takes under a second on a quiet machine; beside four busy processes the worker (nice
5) did not finish one within the former 3 s (the suite run under load lost it). A picture is the
job's record, so an idle worker waits for it; when an agent is stopped, the supervisor's grace
for the agent bounds the wait (``cli/supervisor.py``). Drawn in a process apart, a picture costs
about 1 s more CPU (the process's start), and it may wait for another vehicle's turn to draw
(``vehicle_agent/picture_process.py``); what is not drawn by then stays ordered on disk."""
PR_SET_PDEATHSIG = 1
WARM_TEXT = "一"
"""What ``warm`` plans: one stroke is enough to import and run every module a plan uses (after it,
the Airshow corpus's characters cost 0.02-0.05 s CPU each, cold 1.0-1.3 s, of which 0.6 s was
``scipy.signal`` until ``vehicles/quadrotor_brush/control/tip.py`` filtered on its own)."""

log = logging.getLogger("vehicle_agent.plan_worker")


class Worker:
    """The requests' handlers (imports the heavy modules on ``init``).

    An agent's worker is told its vehicle on ``init``; a fleet host's workers serve every
    vehicle of the host (``init`` without a vehicle), each request wrapped as
    ``("vehicle", vehicle_id, request)``, the vehicle's setup made on its first request."""

    def __init__(self) -> None:
        self._show: Any = None
        self._time_scale: float | None = None
        self._setups: dict[str, Any] = {}
        self._pictures: dict[str, Any] = {}
        self._vehicle_id: str | None = None

    def handle(self, request: tuple[Any, ...]) -> Any:
        """The value answering ``request`` (raises what the work raises)."""
        name = request[0]
        if name == "init":
            return self._init(*request[1:])
        if name == "loaded":
            return loaded_modules(request[1])
        if self._show is None:
            raise RuntimeError("the planning worker was not told its show")
        if name == "vehicle":
            self._select(request[1])
            return self.handle(request[2])
        if self._vehicle_id is None:
            raise RuntimeError("the planning worker was not told its vehicle")
        setup, pictures = self._setups[self._vehicle_id], self._pictures[self._vehicle_id]
        if name == "prepare":
            return self._prepare(setup, request[1])
        if name == "warm":
            return self._warm(setup)
        from vehicle_agent import jobs

        prepared = _opened(request[1])
        if name == "measure":
            return jobs.job_metrics(setup, prepared, request[2])
        if name == "archive":
            where = jobs.archive_job(setup, pictures, prepared, *request[2:])
            return str(where)
        raise ValueError(f"the planning worker has no request {name!r}")

    def close(self) -> None:
        """Wait for the pictures still being drawn."""
        for pictures in self._pictures.values():
            pictures.wait(PICTURE_WAIT_S)

    def _init(self, show: Any, vehicle_id: str | None, time_scale: float) -> None:
        self._show, self._time_scale = show, time_scale
        if vehicle_id is not None:
            self._select(vehicle_id)

    def _select(self, vehicle_id: str) -> None:
        """Work for ``vehicle_id`` from now on (its setup and picture thread made once)."""
        if vehicle_id not in self._setups:
            from vehicle_agent.job_picture import PictureWorker
            from vehicle_agent.setup import vehicle_setup

            setup = vehicle_setup(self._show, vehicle_id, time_scale=self._time_scale)
            self._setups[vehicle_id] = setup
            self._pictures[vehicle_id] = PictureWorker(vehicle_id)
        self._vehicle_id = vehicle_id

    def _warm(self, setup: Any) -> None:
        """Plan :data:`WARM_TEXT` as a job is planned (the kind's plan and its command
        reference), touching no file: the pace model is left alone."""
        from planner.glyphs import text_glyph
        from vehicles.jobs import plan_job

        plan = plan_job(setup.show, setup.vehicle_id, text_glyph(WARM_TEXT)).plan
        setup.kind.command_reference(plan, setup.settings)
        gc.freeze()  # modules and setups live as long as the worker: out of every collection

    def _prepare(self, setup: Any, assignment: Any) -> Any:
        from vehicle_agent.jobs import prepare_job

        prepared = prepare_job(setup, assignment)
        sealed = SealedContext(pickle.dumps(prepared.context, protocol=pickle.HIGHEST_PROTOCOL))
        return replace(prepared, context=sealed)


def loaded_modules(prefixes: tuple[str, ...]) -> list[str]:
    """The modules this process has imported whose names are or start with one of
    ``prefixes`` (``"scipy.signal"`` matches ``scipy.signal`` and ``scipy.signal._sigtools``)."""
    return sorted(
        name for name in sys.modules if any(name == p or name.startswith(f"{p}.") for p in prefixes)
    )


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
        if _innermost(request)[0] == "archive":  # a job's end: off the plan's path
            give_back()


def _innermost(request: tuple[Any, ...]) -> tuple[Any, ...]:
    """The request itself, out of a fleet host's ``("vehicle", vehicle_id, request)``."""
    while request[0] == "vehicle" and len(request) == 3 and isinstance(request[2], tuple):
        if not request[2]:
            break
        request = request[2]
    return request


def give_back() -> None:
    """Collect the garbage (a job leaves cycles that only a full collection frees) and give
    the free heap back to the system (``malloc_trim``: freed pages inside the heap stay mapped
    otherwise). Measured in one process after three Airshow jobs and their pictures, when the
    worker still drew them: 217 MiB, 204 MiB trimmed alone, 170 MiB collected and trimmed; the
    collection costs 0.14 s CPU once the warm-up's objects are frozen (0.23 s before)."""
    gc.collect()
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL("libc.so.6").malloc_trim(0)


PLAN_NICE = 5
"""The planning worker's nice value (see :func:`main`)."""


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
    # Below the control loop, but never starved: SCHED_BATCH (it does not preempt on its own
    # wake-ups) at nice 5. SCHED_IDLE, used before, gave the loop its best period jitter (p99
    # 1.7-1.8 ms as on a bare loop, against 2.7 ms at plain nice 5, benchmarks/bench_agent.py),
    # but planning got no CPU at all while anything else on the machine was busy: with four busy
    # loops beside it on 2 cores, one character's plan had not come back in 300 s
    # (tests/test_agent_worker.py), and a show on a loaded laptop would stop taking jobs.
    os.sched_setscheduler(0, os.SCHED_BATCH, os.sched_param(0))
    os.nice(PLAN_NICE)
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
