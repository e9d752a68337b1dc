"""``skyquill fleet SHOW.yaml --vehicles ID,ID,...``: a fleet host, the agents of several
simulated vehicles in one process (``vehicle_agent/fleet.py``); ``skyquill up`` starts it for a
show with ``fleet_hosts``."""

from __future__ import annotations

import argparse
import contextlib
import logging
import os
import sys
from pathlib import Path

NAME = "fleet"
HELP = "Run the agents of several simulated vehicles in one process (a fleet host)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--vehicles",
        required=True,
        metavar="ID,ID,...",
        help="the simulated vehicles this host carries, comma-separated",
    )
    parser.add_argument(
        "--time-scale",
        type=float,
        default=None,
        help="simulated seconds per wall second (default: time_scale of the show file)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the first vehicle's world")
    parser.add_argument(
        "--workers", type=int, default=None, help="planning workers (default: min(2, cores))"
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log every command")


def run(args: argparse.Namespace) -> int:
    import asyncio

    from showfile import ShowError, load_show
    from vehicle_agent.fleet import FleetError, FleetHost
    from vehicle_agent.stop_signals import run_landing_first

    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(asctime)s fleet %(levelname)s %(message)s",
        stream=sys.stderr,
    )
    vehicle_ids = [v.strip() for v in args.vehicles.split(",") if v.strip()]
    try:
        show = load_show(args.show)
        if args.time_scale is not None and not args.time_scale > 0.0:
            raise ValueError("--time-scale must be positive")
        if args.workers is not None and args.workers < 1:
            raise ValueError("--workers must be at least 1")
        host = FleetHost(
            show, vehicle_ids, time_scale=args.time_scale, seed=args.seed, workers=args.workers
        )
    except (ShowError, FleetError, KeyError, ValueError) as exc:
        print(f"skyquill fleet: {exc}", file=sys.stderr)
        return 2
    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(run_landing_first(host))
    # Every session is closed and the pictures written: skip the interpreter's teardown (about a
    # second of CPU unloading modules), as an agent does.
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
