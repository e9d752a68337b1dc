"""The fleet host process of ``bench_fleet_host.py``: ``vehicle_agent.fleet.FleetHost`` as
``skyquill fleet`` runs it, plus a task writing its figures once a second.

    python benchmarks/fleet_host_child.py SHOW ID,ID,... STATS [--profile PATH]

``STATS`` gets one JSON line a second (:func:`record_figures`); ``--profile`` writes a cProfile
of the process there at the end. SIGTERM or SIGINT stops it.
"""

from __future__ import annotations

import argparse
import asyncio
import itertools
import json
import operator
import os
import signal
import sys
import time
from functools import partial
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from showfile import load_show

PERIOD_S = 0.01
"""Control period of the simulated vehicles in [s] (their ticks' jitter is measured against it)."""
STATS_PERIOD_S = 1.0
"""Period in [s] of the figures' lines."""


async def record_figures(host: object, path: Path) -> None:
    """Once a second, one JSON line: ticks run and due of the vehicles awake throughout the
    second, their tick jitter, the loop's lag, the fleet steps that stepped them."""
    from vehicle_agent.fleet import FleetHost

    assert isinstance(host, FleetHost)
    lags: list[float] = []

    async def probe() -> None:
        while True:
            started = time.monotonic()
            await asyncio.sleep(PERIOD_S)
            lags.append((time.monotonic() - started - PERIOD_S) * 1e3)

    prober = asyncio.create_task(probe())
    before: dict[str, tuple[int, bool]] = {}
    wall_s = time.monotonic()
    with path.open("a") as out:
        try:
            while True:
                await asyncio.sleep(STATS_PERIOD_S)
                now_s = time.monotonic()
                ran = due = 0.0
                jitter: list[float] = []
                awake = 0
                for vehicle_id, service in list(host.services.items()):
                    tick, resting = service.clock.tick, service.resting
                    last = before.get(vehicle_id)
                    before[vehicle_id] = (tick, resting)
                    if last is None or last[1] or resting:
                        continue
                    awake += 1
                    ran += tick - last[0]
                    due += (now_s - wall_s) / service.clock.wall_period_s
                    starts = list(
                        itertools.takewhile(
                            partial(operator.lt, wall_s), reversed(service.tick_starts_s)
                        )
                    )[::-1]  # the last second's, newest first: not a scan of the history
                    jitter += [abs(b - a - PERIOD_S) * 1e3 for a, b in itertools.pairwise(starts)]
                line = {
                    "t": now_s,
                    "awake": awake,
                    "ran": ran,
                    "due": due,
                    "jitter_ms": [round(j, 2) for j in jitter],
                    "lag_ms": [round(lag, 2) for lag in lags],
                    "restarts": sum(host.restarts.values()),
                    "steps": host.rounds.steps,
                }
                lags.clear()
                out.write(json.dumps(line) + "\n")
                out.flush()
                wall_s = now_s
        finally:
            prober.cancel()


def child_main(
    show_path: Path, vehicle_ids: list[str], stats: Path, profile: Path | None = None
) -> None:
    """The fleet host of a case; with ``profile``, a cProfile of it written there at the end."""
    from vehicle_agent.fleet import FleetHost

    host = FleetHost(load_show(show_path), vehicle_ids)

    async def main() -> None:
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        figures = asyncio.create_task(record_figures(host, stats))
        await host.run(stop)
        figures.cancel()

    if profile is None:
        asyncio.run(main())
    else:
        import cProfile

        # The loop thread's CPU time, not wall: a wall-clock profile of a process whose threads
        # wait for the interpreter lock charges those waits to whatever held it (a geofence
        # check of 2 us showed 44 us).
        profiler = cProfile.Profile(time.thread_time)
        profiler.runcall(asyncio.run, main())
        profiler.dump_stats(str(profile))
    os._exit(0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("show", type=Path)
    parser.add_argument("ids", help="comma-separated vehicle ids")
    parser.add_argument("stats", type=Path)
    parser.add_argument("--profile", type=Path)
    args = parser.parse_args()
    child_main(args.show, args.ids.split(","), args.stats, args.profile)


if __name__ == "__main__":
    main()
