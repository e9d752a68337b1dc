"""``skyquill orchestrator SHOW.yaml``: the show's job queue, assignment and recording."""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path

NAME = "orchestrator"
HELP = "Run a show's orchestrator (queue, assignment, presence, SQLite, MCAP recording)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--role",
        choices=["client", "peer", "router"],
        default="client",
        help="how to join Zenoh: client of the show's router (default), or host the router",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="log every decision")


def run(args: argparse.Namespace) -> int:
    from bus.session import SessionOpenError
    from orchestrator.app import run_orchestrator
    from orchestrator.store import StoreError
    from showfile import ShowError, load_show

    logging.basicConfig(
        level=logging.INFO if args.verbose else logging.WARNING,
        format="%(asctime)s orchestrator %(levelname)s %(message)s",
    )
    try:
        show = load_show(args.show)
        return run_orchestrator(show, role=args.role)
    except (ShowError, SessionOpenError, StoreError) as exc:
        print(f"skyquill orchestrator: {exc}", file=sys.stderr)
        return 2
