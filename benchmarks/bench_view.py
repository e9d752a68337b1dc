"""What Foxglove viewers cost a running show: telemetry rate and jitter with 0 and 5 viewers.

    .venv/bin/python benchmarks/bench_view.py [--seconds 40] [--viewers 5]

The Airshow show (four vehicles, secured) runs as real processes; four characters keep the
vehicles writing in each phase (a stand-in crew replaces the sheets between them). An
operator's session takes every vehicle's telemetry (20 Hz) and measures, while vehicles write,
the rate received and the jitter of the gaps between samples (|gap - 50 ms|, p50 and p99).
Phase 1 has no viewer; phase 2 runs ``skyquill view`` with ``--viewers`` WebSocket clients
subscribed to every channel it advertises. The view is its own process, so its cost to the
show is the CPU it takes on the same machine: printed too.
"""

from __future__ import annotations

import argparse
import asyncio
import itertools
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import websockets  # noqa: E402
from bench_show import submit_char, wait_ready  # noqa: E402

from bus.messages import Telemetry  # noqa: E402
from bus.pubsub import subscribe  # noqa: E402
from bus.session import free_tcp_endpoint  # noqa: E402
from cli.showrun import ShowRun, Stagehand, derived_show  # noqa: E402

SHOW = ROOT / "shows" / "airshow-2014.yaml"
PERIOD_S = 0.05
"""Telemetry period of an agent, [s] (20 Hz)."""
CHARS = "永光马A"


class Arrivals:
    """Arrival times of each vehicle's telemetry while it writes (thread-safe)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.times: dict[str, list[float]] = defaultdict(list)
        self.recording = False

    def take(self, _key: str, t: Telemetry) -> None:
        if self.recording and t.state == "writing":
            with self.lock:
                self.times[t.vehicle_id].append(time.monotonic())

    def summary(self) -> tuple[float, float, float]:
        """(rate per vehicle [Hz], jitter p50 [ms], jitter p99 [ms]) over runs of writing."""
        gaps, rates = [], []
        with self.lock:
            for stamps in self.times.values():
                dt = [b - a for a, b in itertools.pairwise(stamps) if b - a < 1.0]
                gaps += [abs(d - PERIOD_S) * 1e3 for d in dt]
                if dt:
                    rates.append(1.0 / statistics.fmean(dt))
        if not gaps:
            return 0.0, 0.0, 0.0
        q = statistics.quantiles(gaps, n=100)
        return statistics.fmean(rates), q[49], q[98]


async def _viewer(url: str, stop: threading.Event, received: list[int]) -> None:
    async with websockets.connect(url, subprotocols=["foxglove.sdk.v1"]) as ws:  # type: ignore[list-item]
        subscribed: set[int] = set()
        while not stop.is_set():
            try:
                frame = await asyncio.wait_for(ws.recv(), timeout=0.5)
            except TimeoutError:
                continue
            except websockets.ConnectionClosed:
                return  # the view was stopped
            if isinstance(frame, str):
                op = json.loads(frame)
                if op.get("op") == "advertise":
                    new = [c["id"] for c in op["channels"] if c["id"] not in subscribed]
                    subs = [{"id": cid, "channelId": cid} for cid in new]
                    subscribed.update(new)
                    await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
            else:
                received[0] += 1


def _cpu_s(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _phase(run: ShowRun, session: object, arrivals: Arrivals, seconds: float, start: int) -> None:
    for i, char in enumerate(CHARS):
        submit_char(session, run, char, start + i)  # type: ignore[arg-type]
    time.sleep(8.0)  # take-off and transit
    arrivals.recording = True
    time.sleep(seconds)
    arrivals.recording = False
    wait_ready(run, session, 4, 300.0)  # type: ignore[arg-type]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=40.0, help="measured per phase (40)")
    parser.add_argument("--viewers", type=int, default=5, help="WebSocket viewers (5)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path, show = derived_show(SHOW, Path(tmp))
        with (
            ShowRun(path, show, log_dir=Path(tmp) / "logs") as run,
            run.client() as session,
            Stagehand(session, run.keys),  # the crew's fresh sheets (per character)
        ):
            wait_ready(run, session, 4, 120.0)
            quiet, viewed = Arrivals(), Arrivals()
            subscribe(session, run.keys.telemetry_all, Telemetry, quiet.take)
            subscribe(session, run.keys.telemetry_all, Telemetry, viewed.take)
            _phase(run, session, quiet, args.seconds, 0)
            load_quiet = os.getloadavg()[0]
            port = int(free_tcp_endpoint().rsplit(":", 1)[1])
            view = subprocess.Popen(
                [sys.executable, "-m", "cli.main", "view", str(path), "--port", str(port)],
                stdout=subprocess.PIPE,
                text=True,
            )
            stop, received = threading.Event(), [0]
            try:
                view.stdout.readline()  # type: ignore[union-attr]
                url = f"ws://127.0.0.1:{port}"
                threads = [
                    threading.Thread(target=asyncio.run, args=(_viewer(url, stop, received),))
                    for _ in range(args.viewers)
                ]
                for thread in threads:
                    thread.start()
                cpu0, t0 = _cpu_s(view.pid), time.monotonic()
                _phase(run, session, viewed, args.seconds, 100)
                view_cpu = (_cpu_s(view.pid) - cpu0) / (time.monotonic() - t0)
                load_viewed = os.getloadavg()[0]
            finally:
                stop.set()
                view.terminate()
                view.wait(10)
    (rate0, p50_0, p99_0), (rate1, p50_1, p99_1) = quiet.summary(), viewed.summary()
    print(f"telemetry while writing, 4 vehicles, {args.seconds:.0f} s per phase:")
    print(f"  0 viewers: {rate0:.2f} Hz per vehicle, jitter p50 {p50_0:.2f} ms, p99 {p99_0:.2f} ms"
          f"  (load {load_quiet:.1f})")  # fmt: skip
    print(f"  {args.viewers} viewers: {rate1:.2f} Hz per vehicle, jitter p50 {p50_1:.2f} ms, "
          f"p99 {p99_1:.2f} ms  (load {load_viewed:.1f})")  # fmt: skip
    print(f"  ratio viewed/quiet: rate x{rate1 / max(rate0, 1e-9):.3f}, jitter p99 "
          f"x{p99_1 / max(p99_0, 1e-9):.2f}; the view took {100 * view_cpu:.1f} % of a core, "
          f"its viewers received {received[0]} messages")  # fmt: skip
    return 0


if __name__ == "__main__":
    sys.exit(main())
