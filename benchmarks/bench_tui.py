"""Frame time of the operator console with N vehicles sending telemetry at 20 Hz.

Runs the real console headless (Textual's test driver) and feeds it telemetry of N vehicles writing
at once, through a real Zenoh router on loopback (or straight into the inbox with ``--direct``).
Prints the redraw time, the event-loop lag (how late a 10 ms timer fires: what an operator feels
as key latency), frames per second, CPU use and dropped samples.

    .venv/bin/python benchmarks/bench_tui.py [--vehicles 100] [--seconds 5] [--direct]
"""

from __future__ import annotations

import argparse
import asyncio
import multiprocessing
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bus.keys import ShowKeys
from bus.messages import Telemetry
from bus.pubsub import MessagePublisher, declare_token
from bus.session import BusSettings, loopback_settings, open_session
from tui.app import ConsoleApp
from tui.demo import demo_settings, demo_telemetry
from tui.link import ConsoleLink
from tui.settings import ConsoleSettings


def feed(
    settings: ConsoleSettings,
    send: Callable[[Telemetry], None],
    seconds: float,
    rate_hz: float,
    stop: threading.Event,
) -> int:
    """Send every vehicle's next telemetry sample at ``rate_hz`` (on this thread); returns count."""
    paths = [
        demo_telemetry(spec.vehicle_id, board, f"job-{spec.vehicle_id}", 1.0)
        for spec, board in zip(settings.vehicles, settings.boards, strict=True)
    ]
    sent, tick, start = 0, 0, time.perf_counter()
    while not stop.is_set() and time.perf_counter() - start < seconds:
        for path in paths:
            send(path[tick % len(path)])
            sent += 1
        tick += 1
        delay = start + tick / rate_hz - time.perf_counter()
        if delay > 0:
            time.sleep(delay)
    return sent


def pct(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))] if ordered else float("nan")


async def measure(
    app: ConsoleApp, seconds: float, start_feed: Callable[[], int]
) -> dict[str, float]:
    frame_times: list[float] = []
    original = app.redraw

    def timed_redraw() -> None:
        original()
        frame_times.append(app.frame_time_s)

    app.redraw = timed_redraw  # type: ignore[method-assign]
    lags: list[float] = []
    async with app.run_test(size=(200, 60)) as pilot:
        await pilot.pause(0.2)
        frames_before, cpu_before = app.frames, time.process_time()
        feeder = asyncio.get_running_loop().run_in_executor(None, start_feed)
        t_end = time.perf_counter() + seconds
        while time.perf_counter() < t_end:
            t0 = time.perf_counter()
            await asyncio.sleep(0.01)
            lags.append(time.perf_counter() - t0 - 0.01)
        sent = await feeder
        cpu = time.process_time() - cpu_before
        frames = app.frames - frames_before
        await pilot.pause(0.1)
    return {
        "sent": sent,
        "frames": frames,
        "cpu": cpu,
        "dropped": app.inbox.dropped,
        "frame_p50": pct(frame_times, 0.5),
        "frame_p95": pct(frame_times, 0.95),
        "frame_max": max(frame_times, default=float("nan")),
        "lag_p50": pct(lags, 0.5),
        "lag_p95": pct(lags, 0.95),
        "lag_max": max(lags, default=0.0),
        "tracked": sum(
            t.count for v in app.settings.vehicles if (t := app.model.track(v.vehicle_id))
        ),
    }


def publish_fleet(bus: BusSettings, vehicles: int, seconds: float, rate_hz: float) -> None:
    """Child process: the show's router and N vehicles publishing telemetry."""
    settings = demo_settings(vehicles)
    keys = ShowKeys(settings.show_id)
    with open_session(bus, role="router") as router:
        tokens = [
            declare_token(router, keys.vehicle_alive(v.vehicle_id)) for v in settings.vehicles
        ]
        publishers = {
            v.vehicle_id: MessagePublisher(router, keys.telemetry(v.vehicle_id))
            for v in settings.vehicles
        }
        time.sleep(1.0)  # let the console connect
        feed(
            settings, lambda t: publishers[t.vehicle_id].put(t), seconds, rate_hz, threading.Event()
        )
        for token in tokens:
            token.undeclare()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--rate-hz", type=float, default=20.0)
    parser.add_argument("--redraw-hz", type=float, default=20.0)
    parser.add_argument("--direct", action="store_true", help="skip Zenoh: feed the inbox")
    args = parser.parse_args()
    base = demo_settings(args.vehicles)
    settings = ConsoleSettings(base.show_id, base.boards, base.vehicles, redraw_hz=args.redraw_hz)
    if args.direct:
        app = ConsoleApp(settings)
        result = asyncio.run(
            measure(
                app,
                args.seconds,
                lambda: feed(settings, app._deliver, args.seconds, args.rate_hz, threading.Event()),
            )
        )
    else:
        bus = loopback_settings()
        child = multiprocessing.get_context("spawn").Process(
            target=publish_fleet, args=(bus, args.vehicles, args.seconds + 1.0, args.rate_hz)
        )
        child.start()
        try:
            with open_session(bus, role="client", open_timeout_s=20.0) as session:
                app = ConsoleApp(settings, link=ConsoleLink(session, ShowKeys(settings.show_id)))
                result = asyncio.run(measure(app, args.seconds, lambda: 0))
                result["sent"] = args.vehicles * args.rate_hz * args.seconds
        finally:
            child.join(timeout=30)
            if child.is_alive():
                child.terminate()
    seconds = args.seconds
    via = "the inbox, fed in-process" if args.direct else "Zenoh, published by another process"
    print(
        f"console: {args.vehicles} vehicles x {args.rate_hz:g} Hz telemetry for {seconds:g} s "
        f"via {via}, redraw limit {args.redraw_hz:g} Hz, 200x60 terminal"
    )
    print(
        f"  samples sent ~{result['sent']:.0f} ({result['sent'] / seconds:.0f}/s), "
        f"merged into tracks {result['tracked']:.0f}, dropped {result['dropped']:.0f}"
    )
    print(f"  frames {result['frames']:.0f} ({result['frames'] / seconds:.1f}/s)")
    print(
        f"  frame time (redraw of all views) p50 {1e3 * result['frame_p50']:.2f} ms, "
        f"p95 {1e3 * result['frame_p95']:.2f} ms, max {1e3 * result['frame_max']:.2f} ms"
    )
    print(
        f"  event-loop lag (key latency) p50 {1e3 * result['lag_p50']:.2f} ms, "
        f"p95 {1e3 * result['lag_p95']:.2f} ms, max {1e3 * result['lag_max']:.2f} ms"
    )
    print(f"  CPU of the console process {100 * result['cpu'] / seconds:.0f}% of one core")


if __name__ == "__main__":
    main()
