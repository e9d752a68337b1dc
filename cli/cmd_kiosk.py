"""``skyquill kiosk SHOW.yaml``: the public web kiosk; prints the page's URL when it serves.

With the show's ``crew`` certificate it opens a second session under that identity and serves
the crew's page on ``/crew`` (phones paired with ``skyquill crew SHOW --pair NAME``); without
it, it says so and serves the public's page alone."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "kiosk"
HELP = "Public web kiosk: people draw or type a character and follow it until a drone wrote it."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("--host", help="address to listen on (default: kiosk.host of the show)")
    parser.add_argument(
        "--port", type=int, help="TCP port (default: kiosk.port of the show; 0: any free port)"
    )
    parser.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help="Zenoh endpoint of the show's router (repeatable; default: zenoh.connect of the show)",
    )
    parser.add_argument(
        "--role",
        choices=("peer", "client"),
        default="peer",
        help="Zenoh mode: peer (default) starts before the router is up; client needs it at start",
    )


def run(args: argparse.Namespace) -> int:
    import dataclasses

    from bus.session import SessionOpenError
    from kiosk.service import run_kiosk
    from kiosk.settings import settings_from_show
    from showfile import ShowError, load_show
    from trust.files import KeysError
    from trust.settings import session_settings

    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill kiosk: {exc}", file=sys.stderr)
        return 2
    if args.port is not None and not 0 <= args.port <= 65535:
        print("skyquill kiosk: --port must be within 0..65535", file=sys.stderr)
        return 2
    settings = settings_from_show(show, port=args.port)
    if args.host:
        settings = dataclasses.replace(settings, host=args.host)
    try:
        crew = session_settings(show, "crew")
    except KeysError as exc:
        print(f"skyquill kiosk: no crew page: {exc}", file=sys.stderr)
        crew = None
    try:
        run_kiosk(
            settings,
            session_settings(show, "kiosk"),
            role=args.role,
            connect=args.connect,
            on_started=lambda url: print(url, flush=True),
            crew_zenoh=crew,
        )
    except SessionOpenError as exc:
        print(f"skyquill kiosk: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"skyquill kiosk: cannot listen on {settings.host}:{settings.port}: {exc}",
              file=sys.stderr)  # fmt: skip
        return 1
    return 0
