"""``skyquill agent SHOW.yaml --vehicle ID``: one vehicle's agent process."""

from __future__ import annotations

import argparse
import logging
import os
import sys
from pathlib import Path

NAME = "agent"
HELP = "Run one vehicle's agent: takes jobs from the orchestrator, plans, flies, reports."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("--vehicle", required=True, metavar="ID", help="vehicle id in the show")
    parser.add_argument(
        "--time-scale",
        type=float,
        default=None,
        help="simulated seconds per wall second (default: time_scale of the show file)",
    )
    parser.add_argument("--seed", type=int, default=0, help="seed of the simulated world")
    parser.add_argument("-v", "--verbose", action="store_true", help="log every command")


def run(args: argparse.Namespace) -> int:
    from bus.session import SessionOpenError
    from showfile import ShowError, load_show
    from vehicle_agent.agent import make_backend, run_agent_blocking
    from vehicle_agent.events import EventOutbox
    from vehicle_agent.setup import vehicle_setup

    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format=f"%(asctime)s agent {args.vehicle} %(levelname)s %(message)s",
        stream=sys.stderr,
    )
    try:
        show = load_show(args.show)
        if args.time_scale is not None and not args.time_scale > 0.0:
            raise ValueError("--time-scale must be positive")
        setup = vehicle_setup(show, args.vehicle, time_scale=args.time_scale)
    except (ShowError, KeyError, ValueError) as exc:
        print(f"skyquill agent: {exc}", file=sys.stderr)
        return 2
    try:
        events = EventOutbox(setup.vehicle_id)
        backend = make_backend(setup, seed=args.seed, on_text=events.autopilot_text)
        run_agent_blocking(setup, backend, events)
    except SessionOpenError as exc:
        print(f"skyquill agent: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        pass
    # The session is closed and the job pictures are written: skip the interpreter's teardown,
    # which spends about a second of CPU unloading modules (50 agents stopping at once on two
    # cores then overrun their grace period).
    logging.shutdown()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(0)
