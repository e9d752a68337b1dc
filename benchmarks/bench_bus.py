"""Bus numbers: telemetry latency agent -> orchestrator, and submissions acknowledged per second.

    .venv/bin/python benchmarks/bench_bus.py [--publishers 4 50] [--seconds 5] [--submissions 200]

Telemetry: a child process opens one Zenoh client session per simulated agent and publishes
Telemetry at 20 Hz each (stamped with the wall clock); this process hosts the router and receives
them the way the orchestrator does (subscriber callback -> bridge channel -> asyncio loop). The
latency is the time from the publisher's ``put`` to the sample being taken in the event loop.
Submissions: the real orchestrator service (SQLite WAL, synchronous=FULL, MCAP recording) in a
thread; a client sends valid text submissions one after the other, then 8 at a time.
"""

from __future__ import annotations

import argparse
import asyncio
import multiprocessing
import statistics
import sys
import tempfile
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bus.bridge import RingChannel  # noqa: E402
from bus.keys import ShowKeys  # noqa: E402
from bus.messages import ShowSnapshot, SubmitReply, SubmitRequest, Telemetry  # noqa: E402
from bus.pubsub import MessagePublisher, subscribe  # noqa: E402
from bus.rpc import aquery_one, query, query_one  # noqa: E402
from bus.session import BusSettings, free_tcp_endpoint, open_session  # noqa: E402

KEYS = ShowKeys("bench")
RATE_HZ = 20.0


def _publishers(endpoint: str, count: int, seconds: float, ready: object) -> None:
    settings = BusSettings(router_listen=[], connect=[endpoint])
    sessions = [open_session(settings, role="client") for _ in range(count)]
    pubs = [MessagePublisher(s, KEYS.telemetry(f"v{i}")) for i, s in enumerate(sessions)]
    ready.set()  # type: ignore[attr-defined]
    t0 = time.monotonic()
    tick = 0
    while time.monotonic() - t0 < seconds:
        tick += 1
        for i, pub in enumerate(pubs):
            pub.put(
                Telemetry(
                    vehicle_id=f"v{i}",
                    t_s=time.time(),
                    state="writing",
                    position_m_enu=(0.0, 0.0, 1.0),
                    velocity_mps_enu=(0.0, 0.0, 0.0),
                )
            )
        time.sleep(max(0.0, t0 + tick / RATE_HZ - time.monotonic()))
    for s in sessions:
        s.close()


async def _receive(session: object, seconds: float, expected: int) -> tuple[list[float], int]:
    ring: RingChannel[tuple[Telemetry, float]] = RingChannel(4096)
    sub = subscribe(
        session,  # type: ignore[arg-type]
        KEYS.telemetry_all,
        Telemetry,
        lambda _, m: ring.push((m, 0.0)),
    )
    latencies: list[float] = []
    deadline = time.monotonic() + seconds + 2.0
    while time.monotonic() < deadline and len(latencies) < expected:
        try:
            msg, _ = await asyncio.wait_for(ring.get(), timeout=0.5)
        except TimeoutError:
            continue
        latencies.append(time.time() - msg.t_s)
    sub.undeclare()
    return latencies, ring.dropped


def bench_telemetry(count: int, seconds: float) -> None:
    endpoint = free_tcp_endpoint()
    settings = BusSettings(router_listen=[endpoint], connect=[endpoint])
    ctx = multiprocessing.get_context("spawn")
    ready = ctx.Event()
    with open_session(settings, role="router") as router:
        child = ctx.Process(target=_publishers, args=(endpoint, count, seconds, ready))
        child.start()
        ready.wait(60)
        expected = int(count * RATE_HZ * seconds)
        latencies, dropped = asyncio.run(_receive(router, seconds, expected))
        child.join(30)
    warm = latencies[count * 4 :]  # skip the first 0.2 s (connections settling)
    if not warm:
        print(f"{count:3d} publishers: no samples")
        return
    q = statistics.quantiles(warm, n=100)
    print(
        f"{count:3d} publishers x {RATE_HZ:.0f} Hz: {len(latencies)}/{expected} received, "
        f"dropped {dropped}, latency p50 {1e3 * q[49]:.2f} ms, p99 {1e3 * q[98]:.2f} ms, "
        f"max {1e3 * max(warm):.2f} ms"
    )


def bench_submissions(total: int) -> None:
    from orchestrator.app import serve_show
    from showfile import load_show

    with tempfile.TemporaryDirectory() as tmp:
        endpoint = free_tcp_endpoint()
        base = load_show(ROOT / "shows" / "airshow-2014.yaml")
        show = base.model_copy(
            update={
                "show_id": "bench",
                "zenoh": base.zenoh.model_copy(
                    update={"router_listen": (endpoint,), "connect": (endpoint,)}
                ),
                "storage": base.storage.model_copy(
                    update={"database": Path(tmp) / "db.sqlite3", "recordings_dir": Path(tmp)}
                ),
                "policy": base.policy.model_copy(update={"max_queue": 10 * total}),
            }
        )
        stop_holder: list[tuple[asyncio.AbstractEventLoop, asyncio.Event]] = []

        def serve() -> None:
            async def main() -> None:
                stop = asyncio.Event()
                stop_holder.append((asyncio.get_running_loop(), stop))
                await serve_show(show, role="router", stop=stop)

            asyncio.run(main())

        thread = threading.Thread(target=serve, daemon=True)
        thread.start()
        with open_session(show.zenoh, role="client", open_timeout_s=10) as client:
            while not query(client, KEYS.snapshot, None, ShowSnapshot, timeout_s=0.5):
                time.sleep(0.05)
            request = SubmitRequest(text="永", client_id="bench")
            t0 = time.perf_counter()
            for _ in range(total):
                assert query_one(client, KEYS.submit, request, SubmitReply).ok
            sequential = total / (time.perf_counter() - t0)

            async def concurrent() -> float:
                sem = asyncio.Semaphore(8)

                async def one() -> None:
                    async with sem:
                        reply = await aquery_one(client, KEYS.submit, request, SubmitReply)
                        assert reply.ok

                t1 = time.perf_counter()
                await asyncio.gather(*(one() for _ in range(total)))
                return total / (time.perf_counter() - t1)

            parallel = asyncio.run(concurrent())
        loop, stop = stop_holder[0]
        loop.call_soon_threadsafe(stop.set)
        thread.join(30)
    print(
        f"submissions acknowledged (stored, fsynced, recorded): {sequential:.0f}/s one at a time,"
        f" {parallel:.0f}/s with 8 in flight ({total} each)"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--publishers", type=int, nargs="+", default=[4, 50])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--submissions", type=int, default=200)
    args = parser.parse_args()
    for count in args.publishers:
        bench_telemetry(count, args.seconds)
    bench_submissions(args.submissions)


if __name__ == "__main__":
    main()
