"""``skyquill tui SHOW.yaml``: the operator console in this terminal (works over SSH, 80x24 up)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

NAME = "tui"
HELP = "Operator console: fleet, boards, queue and alerts of a running show, in the terminal."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help="Zenoh endpoint of the show's router, e.g. tcp/10.0.0.2:7447 (repeatable; "
        "default: zenoh.connect of the show file)",
    )
    parser.add_argument(
        "--role",
        choices=("peer", "client"),
        default="peer",
        help="Zenoh mode: peer (default) starts even before the show's router is up and "
        "joins when it appears; client needs the router at start",
    )
    parser.add_argument(
        "--redraw-hz", type=float, default=20.0, help="highest redraw rate (default 20)"
    )
    parser.add_argument(
        "--demo", action="store_true", help="no bus: a made-up fleet, to try the screen"
    )


def run(args: argparse.Namespace) -> int:
    from bus.keys import ShowKeys
    from bus.session import SessionOpenError, open_session
    from showfile import ShowError, load_show
    from trust.settings import session_settings
    from tui.app import ConsoleApp
    from tui.link import ConsoleLink
    from tui.settings import settings_from_show

    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill tui: {exc}", file=sys.stderr)
        return 2
    if not 1.0 <= args.redraw_hz <= 60.0:
        print("skyquill tui: --redraw-hz must be within 1..60", file=sys.stderr)
        return 2
    settings = settings_from_show(show, redraw_hz=args.redraw_hz)
    if args.demo:
        from tui.demo import DEMO_TIME_S, demo_model

        ConsoleApp(settings, model=demo_model(settings), clock=lambda: DEMO_TIME_S).run()
        return 0
    try:
        session = open_session(
            session_settings(show, "operator"), role=args.role, connect=args.connect
        )
    except SessionOpenError as exc:
        print(f"skyquill tui: {exc}", file=sys.stderr)
        return 1
    with session:
        link = ConsoleLink(session, ShowKeys(show.show_id))
        app = ConsoleApp(settings, link=link)
        app.run()
    return app.return_code or 0  # non-zero after a crash: `skyquill up` reopens the console
