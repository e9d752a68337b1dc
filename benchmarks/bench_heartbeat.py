"""The orchestrator's CPU per vehicle status message, in isolation (no router, no agents).

    nice -n 15 .venv/bin/python benchmarks/bench_heartbeat.py [--vehicles 250] [--writing 10]
        [--finished 500] [--rounds 20] [--profile]

A real :class:`~orchestrator.service.OrchestratorService` (real Book, real SQLite store, a
session that drops what is published) holds a show of N vehicles (``bench_stop.wide_show``),
every one alive and heard, M of them writing a job, ``--finished`` finished jobs in memory (a
long show keeps ``MAX_FINAL_JOBS``). A stream of status heartbeats, as the
agents send them (JSON bytes on each vehicle's own key, round robin, nothing changed), goes
through what the orchestrator does with each: the subscriber's decoding and key check in
Zenoh's thread, then the asyncio handler. Printed: CPU per message in [us], and the cores 250
vehicles would take at 1 Hz and at the old 2.7 Hz. The peer, in the same run: ``json.loads`` of
the same payloads (the least any Python consumer does with a message).

Then a job acknowledgement's wait behind a flood: a burst of one heartbeat from every vehicle
arrives in the loop just before an agent's report; printed is how long (wall, this process) the
report's reply took, with the statuses decided in chunks (the orchestrator's way) and, the peer
in the same run, all at once (what reading them from a channel one by one did).

``--profile`` prints cProfile's top functions of the handling.

Measured on the shared 2-core machine under ``nice -n 15`` (250 vehicles, 10 writing), the code
before issue 15's orchestrator work (bf40be4, methods shimmed) -> after:

- 10 jobs in memory (a fresh show): 789 us of CPU per status -> 12 us (json.loads peer 4-7 us,
  about 2x); 250 vehicles at 2.7 Hz: 0.53 -> 0.008 cores. Before, every status swept the fleet
  (``tick_into``: 250 vehicles, each asking for its active job by scanning every job) and
  recomputed every ETA;
- 500 finished jobs in memory (any show past 500 characters): 43,700 us -> 12 us: the scan
  grew with the finished jobs held, so a 250-vehicle show could not keep up with one status;
- a report's reply after a burst of 250 statuses: 3.7-8 ms, against 3.2-6.4 ms with the burst
  decided at once in the same runs (the burst is 3 ms of work now: chunks bound the wait when
  statuses are costlier); before, 250 x 0.8-44 ms (0.2-11 s).
"""

from __future__ import annotations

import argparse
import asyncio
import cProfile
import json
import pstats
import statistics
import sys
import tempfile
import time
from collections.abc import Callable, Coroutine, Iterable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_stop import wide_show  # noqa: E402

from bus.codec import decode, encode  # noqa: E402
from bus.keys import ShowKeys  # noqa: E402
from bus.messages import AgentReport, VehicleStatus  # noqa: E402
from orchestrator.jobs import Job, transition  # noqa: E402
from orchestrator.service import OrchestratorService  # noqa: E402
from orchestrator.store import JobStore  # noqa: E402

Stream = list[tuple[str, bytes]]
"""Statuses as they arrive: (key, JSON payload)."""
Decide = Callable[["OrchestratorService", Iterable[VehicleStatus]], Coroutine[Any, Any, None]]


class DroppingSession:
    """Takes every publication and drops it (the cost measured is the orchestrator's)."""

    def __init__(self) -> None:
        self.puts = 0

    def put(self, key: str, payload: bytes, **_: Any) -> None:
        self.puts += 1


def stored_jobs(show: Any, writing: int, finished: int, now_s: float) -> list[Job]:
    """``finished`` jobs done, then one being written by each of the first ``writing`` vehicles
    (what the orchestrator loads from its database after a long show)."""
    jobs = []
    for k in range(finished + writing):
        job = Job(
            job_id=f"j{k}", seq=k + 1, state="queued", kind="text", text="永", label="永",
            client_id="bench", created_at_s=now_s, updated_at_s=now_s, estimate_s=20.0,
        )  # fmt: skip
        if k < finished:
            job = transition(job, "done", now_s)
        else:
            vehicle = show.vehicles[k - finished]
            job = transition(job, "assigned", now_s, vehicle_id=vehicle.id, board_id=vehicle.board)
            job = transition(job, "writing", now_s)
        jobs.append(job)
    return jobs


def everyone_present(service: OrchestratorService, now_s: float) -> None:
    """Every vehicle's token seen, and its first status (naming its job, if it has one)."""
    book = service.book
    for vid in book.vehicles:
        service.apply(book.liveliness(vid, True, now_s))
        service.apply(book.status(status_of(service, vid), now_s))


def statuses(service: OrchestratorService) -> list[tuple[str, bytes]]:
    """One heartbeat per vehicle as it arrives: (key, JSON bytes), saying what it said last."""
    keys = ShowKeys(service.show.show_id)
    return [
        (keys.vehicle_status(vid), encode(status_of(service, vid))) for vid in service.book.vehicles
    ]


def status_of(service: OrchestratorService, vehicle_id: str) -> VehicleStatus:
    """What ``vehicle_id`` says of itself: idle, or writing the job it was given."""
    view, job = service.book.vehicles[vehicle_id], service.book.active_job_of(vehicle_id)
    return VehicleStatus(
        vehicle_id=vehicle_id,
        kind=view.info.kind,
        state="idle" if job is None else "writing",
        board_id=view.info.board_id,
        job_id=None if job is None else job.job_id,
    )


async def orchestrator_us(service: OrchestratorService, stream: Stream, rounds: int) -> float:
    """CPU per status of the orchestrator's path, [us]: decoded and checked as the subscriber
    does, then decided as the status task does, one round of every vehicle at a time."""
    assert service.statuses is not None
    started = time.process_time()
    for _ in range(rounds):
        for key, payload in stream:
            service.receive_status(key, decode(payload, VehicleStatus))
        await service.decide_statuses(service.statuses.take_nowait().values())
    return (time.process_time() - started) / (rounds * len(stream)) * 1e6


def peer_us(stream: Stream, rounds: int) -> float:
    """CPU per status of ``json.loads``, [us]."""
    started = time.process_time()
    for _ in range(rounds):
        for _key, payload in stream:
            json.loads(payload)
    return (time.process_time() - started) / (rounds * len(stream)) * 1e6


async def decide_at_once(service: OrchestratorService, statuses: Iterable[VehicleStatus]) -> None:
    """The peer of :meth:`OrchestratorService.decide_statuses`: every status without a turn of
    the loop (what a channel read status by status does when a burst is waiting)."""
    for status in statuses:
        service.apply(service.book.status(status, service.clock()))


async def report_wait_s(service: OrchestratorService, stream: Stream, decide: Decide) -> float:
    """Wall time from a report's arrival to its reply when a burst of one status per vehicle
    arrived just before it (both scheduled on the loop, in that order, as from Zenoh)."""
    assert service.statuses is not None
    job = service.book.active_jobs()[0]
    assert job.vehicle_id is not None
    report = AgentReport(
        vehicle_id=job.vehicle_id, job_id=job.job_id, event="progress", progress=0.5
    )
    for key, payload in stream:
        service.receive_status(key, decode(payload, VehicleStatus))
    arrived = time.perf_counter()
    deciding = asyncio.create_task(decide(service, service.statuses.take_nowait().values()))
    await asyncio.create_task(service.on_report(job.vehicle_id, report))
    waited = time.perf_counter() - arrived
    await deciding
    return waited


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--vehicles", type=int, default=250)
    parser.add_argument("--writing", type=int, default=10)
    parser.add_argument("--finished", type=int, default=500)
    parser.add_argument("--rounds", type=int, default=20, help="statuses of every vehicle")
    parser.add_argument("--profile", action="store_true")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        _, show = wide_show(Path(tmp), args.vehicles)
        with JobStore(Path(tmp) / "bench.sqlite3") as store:
            store.save(stored_jobs(show, args.writing, args.finished, time.time()))
            asyncio.run(run(show, store, args))


async def run(show: Any, store: JobStore, args: argparse.Namespace) -> None:
    service = OrchestratorService(show, DroppingSession(), store)  # type: ignore[arg-type]
    service.open_status_intake()
    everyone_present(service, time.time())
    stream = statuses(service)
    peer = peer_us(stream, args.rounds)
    profiler = cProfile.Profile() if args.profile else None
    if profiler is not None:
        profiler.enable()
    ours = await orchestrator_us(service, stream, args.rounds)
    if profiler is not None:
        profiler.disable()
        pstats.Stats(profiler).sort_stats("tottime").print_stats(20)
    n = args.vehicles
    print(
        f"{n} vehicles, {len(service.book.active_jobs())} writing, {len(service.book.jobs)} jobs"
        f" in memory, {args.rounds * n} statuses"
    )
    print(f"status: {ours:.1f} us of CPU, json.loads peer {peer:.1f} us ({ours / peer:.1f}x)")
    for rate_hz in (1.0, 2.7):
        print(f"  {n} vehicles at {rate_hz} Hz: {ours * 1e-6 * n * rate_hz:.3f} cores")
    for name, decide in (("in chunks", decide_in_chunks), ("at once (peer)", decide_at_once)):
        waits_ms = [1e3 * await report_wait_s(service, stream, decide) for _ in range(5)]
        print(
            f"a report's reply after a burst of {n} statuses decided {name}: "
            f"{statistics.median(waits_ms):.2f} ms (median of 5), max {max(waits_ms):.2f} ms"
        )


async def decide_in_chunks(service: OrchestratorService, statuses: Iterable[VehicleStatus]) -> None:
    """The orchestrator's way (``OrchestratorService.decide_statuses``)."""
    await service.decide_statuses(statuses)


if __name__ == "__main__":
    main()
