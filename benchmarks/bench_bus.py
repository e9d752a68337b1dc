"""Bus numbers on the secured default (mutual TLS with the show's keys, access control): telemetry
latency agent -> orchestrator against raw Zenoh, and submissions acknowledged per second.

    nice -n 10 .venv/bin/python benchmarks/bench_bus.py [--publishers 4 50] [--seconds 16]
        [--rounds 8] [--submissions 200] [--skip-telemetry] [--skip-submissions]

Telemetry: the Airshow show widened to as many vehicles as publishers (``bench_stop.wide_show``,
keys made by ``ensure_show_keys``). A child process opens one client session per vehicle, each
under that vehicle's own certificate, and publishes Telemetry on the vehicle's key at 20 Hz (all
vehicles in one burst per period, as a fleet host does), stamped with the wall clock just before
the ``put``. This process hosts the show's router and, as the orchestrator identity, receives the
same stream in ``--rounds`` pairs of alternating phases (``--seconds`` of each mode in all):

- **raw Zenoh** (the peer): a subscriber whose callback only stamps the arrival time and keeps
  the payload (the stamp is read from it after the phase);
- **skyquill**: the orchestrator's intake (``orchestrator.service.subscribe_telemetry``: decode,
  own-key check, ``LatestByKey``) and a reader in the event loop waiting on ``take()``.

Latency, the same for both: wall-clock time from the publisher's stamp to the sample being usable
in the consumer (the raw callback; the skyquill reader after ``take()``). The orchestrator's own
reader then waits 50 ms between takes on purpose (at most 20 telemetry decisions a second); that
wait is its policy, not the path's, and is left out. The first 0.3 s of every phase is skipped.
Printed per count: p50/p99 of each over all rounds, their ratio, the spread of the per-round
ratios, and this process's CPU time per sample (less noisy than wall time on a shared machine).

Submissions: the real orchestrator service (SQLite WAL, synchronous=FULL, MCAP recording) hosting
the router in a thread; the operator identity (no quota) sends valid text submissions one after
the other, then 8 at a time.
"""

from __future__ import annotations

import argparse
import asyncio
import multiprocessing
import os
import statistics
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

import msgspec

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_stop import wide_show  # noqa: E402

from bus.bridge import LatestByKey  # noqa: E402
from bus.keys import ShowKeys  # noqa: E402
from bus.messages import ShowSnapshot, SubmitReply, SubmitRequest, Telemetry  # noqa: E402
from bus.pubsub import MessagePublisher  # noqa: E402
from bus.rpc import aquery_one, query, query_one  # noqa: E402
from bus.session import Session, open_session  # noqa: E402
from cli.showrun import derived_show  # noqa: E402
from orchestrator.service import subscribe_telemetry  # noqa: E402
from showfile import load_show  # noqa: E402
from trust.settings import ensure_show_keys, session_settings  # noqa: E402

RATE_HZ = 20.0
"""Telemetry rate of an agent (ARCHITECTURE.md, time and rates)."""
SETTLE_S = 0.3
"""Skipped at the start of every phase: the subscriber's declaration reaching the router."""
AIRSHOW = ROOT / "shows" / "airshow-2014.yaml"


class _Stamp(msgspec.Struct):
    t_s: float


_stamp = msgspec.json.Decoder(_Stamp)


def _load() -> str:
    return f"load {os.getloadavg()[0]:.1f}"


def _publishers(show_path: Path, ready: object, stop: object) -> None:
    show = load_show(show_path)
    keys = ShowKeys(show.show_id)
    ids = [v.id for v in show.vehicles]
    sessions = [
        open_session(session_settings(show, i), role="client", open_timeout_s=60) for i in ids
    ]
    pubs = [MessagePublisher(s, keys.telemetry(i)) for i, s in zip(ids, sessions, strict=True)]
    ready.set()  # type: ignore[attr-defined]
    t0 = time.monotonic()
    tick = 0
    while not stop.is_set():  # type: ignore[attr-defined]
        tick += 1
        for vehicle_id, pub in zip(ids, pubs, strict=True):
            pub.put(
                Telemetry(
                    vehicle_id=vehicle_id,
                    t_s=time.time(),
                    state="writing",
                    position_m_enu=(0.0, 0.0, 1.0),
                    velocity_mps_enu=(0.0, 0.0, 0.0),
                )
            )
        time.sleep(max(0.0, t0 + tick / RATE_HZ - time.monotonic()))
    for s in sessions:
        s.close()  # type: ignore[no-untyped-call]


@dataclass
class Phase:
    """What one receiving phase measured."""

    latencies_s: list[float] = field(default_factory=list)
    cpu_s: float = 0.0
    """This process's CPU time over the phase, in [s]."""
    samples: int = 0
    """Samples that reached the consumer's code (skyquill: taken and replaced ones)."""


async def _raw_phase(session: Session, key_expr: str, seconds: float) -> Phase:
    arrivals: list[tuple[float, bytes]] = []
    append, now = arrivals.append, time.time
    sub = session.declare_subscriber(key_expr, lambda s: append((now(), s.payload.to_bytes())))
    await asyncio.sleep(SETTLE_S)
    arrivals.clear()
    cpu0 = time.process_time()
    await asyncio.sleep(seconds)
    cpu = time.process_time() - cpu0
    sub.undeclare()  # type: ignore[no-untyped-call]
    kept = list(arrivals)
    lat = [t - _stamp.decode(p).t_s for t, p in kept]
    return Phase(lat, cpu, len(kept))


async def _skyquill_phase(session: Session, keys: ShowKeys, seconds: float) -> Phase:
    latest: LatestByKey[str, Telemetry] = LatestByKey()
    sub = subscribe_telemetry(session, keys, latest)
    await asyncio.sleep(SETTLE_S)
    latest.take_nowait()
    replaced0 = latest.replaced
    phase = Phase()

    async def consume() -> None:
        while True:
            changed = await latest.take()
            now = time.time()
            phase.latencies_s.extend(now - m.t_s for m in changed.values())

    cpu0 = time.process_time()
    reader = asyncio.create_task(consume())
    await asyncio.sleep(seconds)
    reader.cancel()
    phase.cpu_s = time.process_time() - cpu0
    sub.undeclare()  # type: ignore[no-untyped-call]
    phase.samples = len(phase.latencies_s) + latest.replaced - replaced0
    return phase


def _q(values: list[float]) -> tuple[float, float]:
    q = statistics.quantiles(values, n=100)
    return q[49], q[98]


async def _alternate(
    session: Session, keys: ShowKeys, rounds: int, phase_s: float
) -> tuple[list[Phase], list[Phase]]:
    raw, ours = [], []
    for n in range(rounds):  # ABBA order: neither mode always runs first
        first_raw = n % 2 == 0
        for mode_raw in (first_raw, not first_raw):
            if mode_raw:
                raw.append(await _raw_phase(session, keys.telemetry_all, phase_s))
            else:
                ours.append(await _skyquill_phase(session, keys, phase_s))
    return raw, ours


def bench_telemetry(count: int, rounds: int, phase_s: float) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path, show = wide_show(Path(tmp), count)
        ensure_show_keys(show)
        keys = ShowKeys(show.show_id)
        ctx = multiprocessing.get_context("spawn")
        ready, stop = ctx.Event(), ctx.Event()
        with (
            open_session(session_settings(show, "router"), role="router"),
            open_session(session_settings(show, "orchestrator"), role="client") as session,
        ):
            child = ctx.Process(target=_publishers, args=(path, ready, stop))
            child.start()
            if not ready.wait(300):
                child.kill()
                raise SystemExit(f"{count} publishers did not open their sessions in 300 s")
            time.sleep(1.0)
            raw, ours = asyncio.run(_alternate(session, keys, rounds, phase_s))
            stop.set()
            child.join(30)
            if child.is_alive():
                child.kill()
                child.join()
    _report(count, raw, ours, phase_s)


def _report(count: int, raw: list[Phase], ours: list[Phase], phase_s: float) -> None:
    expected = int(count * RATE_HZ * phase_s)
    print(f"{count} publishers x {RATE_HZ:.0f} Hz, {len(raw)} rounds of {phase_s:g} s ({_load()})")
    figures = {}
    for name, phases in (("raw zenoh", raw), ("skyquill ", ours)):
        lat = [x for p in phases for x in p.latencies_s]
        if len(lat) < 2:
            print(f"  {name}: no samples")
            return
        p50, p99 = _q(lat)
        figures[name] = (p50, p99)
        got = ", ".join(f"{p.samples}/{expected}" for p in phases)
        cpu_us = 1e6 * sum(p.cpu_s for p in phases) / max(1, sum(p.samples for p in phases))
        print(
            f"  {name}: p50 {1e3 * p50:.2f} ms, p99 {1e3 * p99:.2f} ms, max {1e3 * max(lat):.2f}"
            f" ms; CPU {cpu_us:.0f} us/sample; samples per round {got}"
        )
    per_round = [
        (_q(o.latencies_s)[0] / _q(r.latencies_s)[0], _q(o.latencies_s)[1] / _q(r.latencies_s)[1])
        for r, o in zip(raw, ours, strict=True)
        if len(r.latencies_s) > 1 and len(o.latencies_s) > 1
    ]
    (r50, r99), (o50, o99) = figures["raw zenoh"], figures["skyquill "]
    spread50 = ", ".join(f"{a:.2f}" for a, _ in per_round)
    spread99 = ", ".join(f"{b:.2f}" for _, b in per_round)
    print(f"  ratio skyquill/raw: p50 {o50 / r50:.2f} (rounds {spread50})")
    print(f"                      p99 {o99 / r99:.2f} (rounds {spread99})")


def bench_submissions(total: int) -> None:
    from orchestrator.app import serve_show

    with tempfile.TemporaryDirectory() as tmp:
        base = load_show(AIRSHOW)
        _, show = derived_show(
            AIRSHOW, Path(tmp), policy=base.policy.model_copy(update={"max_queue": 10 * total})
        )
        ensure_show_keys(show)
        keys = ShowKeys(show.show_id)
        stop_holder: list[tuple[asyncio.AbstractEventLoop, asyncio.Event]] = []

        def serve() -> None:
            async def main() -> None:
                stop = asyncio.Event()
                stop_holder.append((asyncio.get_running_loop(), stop))
                await serve_show(show, role="router", stop=stop)

            asyncio.run(main())

        thread = threading.Thread(target=serve, daemon=True)
        thread.start()
        settings = session_settings(show, "operator")  # the kiosk's quota would refuse a flood
        with open_session(settings, role="client", open_timeout_s=30) as client:
            while not query(client, keys.snapshot, None, ShowSnapshot, timeout_s=0.5):
                time.sleep(0.05)
            request = SubmitRequest(text="永", client_id="bench")
            t0 = time.perf_counter()
            for _ in range(total):
                assert query_one(client, keys.submit, request, SubmitReply).ok
            sequential = total / (time.perf_counter() - t0)

            async def concurrent() -> float:
                sem = asyncio.Semaphore(8)

                async def one() -> None:
                    async with sem:
                        reply = await aquery_one(client, keys.submit, request, SubmitReply)
                        assert reply.ok, reply

                t1 = time.perf_counter()
                await asyncio.gather(*(one() for _ in range(total)))
                return total / (time.perf_counter() - t1)

            parallel = asyncio.run(concurrent())
        loop, stop = stop_holder[0]
        loop.call_soon_threadsafe(stop.set)
        thread.join(30)
    print(
        f"submissions acknowledged (stored, fsynced, recorded; mTLS): {sequential:.0f}/s one at a"
        f" time, {parallel:.0f}/s with 8 in flight ({total} each; {_load()})"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--publishers", type=int, nargs="+", default=[4, 50])
    parser.add_argument("--seconds", type=float, default=16.0, help="of each mode, in all [s]")
    parser.add_argument("--rounds", type=int, default=8, help="raw/skyquill phase pairs")
    parser.add_argument("--submissions", type=int, default=200)
    parser.add_argument("--skip-telemetry", action="store_true")
    parser.add_argument("--skip-submissions", action="store_true")
    args = parser.parse_args()
    if not args.skip_telemetry:
        for count in args.publishers:
            bench_telemetry(count, args.rounds, args.seconds / args.rounds)
    if not args.skip_submissions:
        bench_submissions(args.submissions)


if __name__ == "__main__":
    main()
