"""``skyquill submit SHOW.yaml (--text TEXT | --strokes FILE)``: hand in a character.

Prints the job id as the last word of its output (``submitted ... job j1a2b3c``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

NAME = "submit"
HELP = "Submit a character (typed text or a strokes JSON file); prints the job id last."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    what = parser.add_mutually_exclusive_group(required=True)
    what.add_argument("--text", help="text to write, e.g. 永 or L")
    what.add_argument("--strokes", type=Path, help="strokes JSON file (docs/formats.md)")
    parser.add_argument("--priority", type=int, default=0, help="higher is sooner (-10..10)")
    parser.add_argument("--client-id", default="cli", help="who submits (default: cli)")
    parser.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for a reply")


def run(args: argparse.Namespace) -> int:
    from bus.rpc import NoReplyError, RemoteError
    from bus.session import SessionOpenError
    from orchestrator.client import submit
    from showfile import ShowError, load_show

    try:
        show = load_show(args.show)
        strokes = None
        if args.strokes is not None:
            strokes = json.loads(args.strokes.read_text(encoding="utf-8"))
            if not isinstance(strokes, dict):
                raise ValueError(f"{args.strokes}: a strokes document is a JSON object")
        reply = submit(
            show,
            text=args.text,
            strokes=strokes,
            client_id=args.client_id,
            priority=args.priority,
            timeout_s=args.timeout,
        )
    except (ShowError, SessionOpenError, NoReplyError, OSError, ValueError) as exc:
        print(f"skyquill submit: {exc}", file=sys.stderr)
        return 2
    except RemoteError as exc:
        print(f"skyquill submit: refused: {exc}", file=sys.stderr)
        return 1
    if not reply.ok or reply.job_id is None:
        error = reply.error
        where = ""
        if error is not None:
            parts = [
                f"field {error.field}" if error.field else "",
                f"stroke {error.stroke_index}" if error.stroke_index is not None else "",
                f"point {error.point_index}" if error.point_index is not None else "",
            ]
            where = ", ".join(p for p in parts if p)
        message = error.message if error is not None else "refused"
        print(
            f"skyquill submit: refused ({where}): {message}"
            if where
            else f"skyquill submit: refused: {message}",
            file=sys.stderr,
        )
        return 1
    position = f", position {reply.queue_position}" if reply.queue_position else ""
    eta = f", starts in ~{reply.eta_s:.0f} s" if reply.eta_s is not None else ""
    print(f"submitted ({reply.state}{position}{eta}) job {reply.job_id}")
    return 0
