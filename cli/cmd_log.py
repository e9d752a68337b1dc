"""``skyquill log SHOW.yaml [--since WHEN] [--json | --csv]``: the show's whole event log.

Read from the show's database, read-only (``orchestrator/event_log.py``): it works while the show
runs and after it, with no bus and no orchestrator. One event per line, oldest first:

- text (default): local time, level, kind, vehicle, job, message; every character a terminal
  would act on is shown as a visible stand-in (``tui/safe_text.py``), whatever was stored;
- ``--json``: JSON Lines, one Event per line with ``time`` (ISO 8601, UTC) beside ``time_s``;
- ``--csv``: a header and one row per event, the same fields; a cell a spreadsheet would take for
  a formula (starting with ``=``, ``+``, ``-``, ``@``, tab or carriage return) is prefixed with
  ``'``, as OWASP recommends, since messages carry visitors' text.

``--since`` takes a duration back from now (``90s``, ``15m``, ``2h``, ``1d``) or a moment
(``2026-11-29T14:00``, local time unless it says its zone).
"""

from __future__ import annotations

import argparse
import csv
import datetime
import json
import re
import sys
import time
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bus.messages import Event

NAME = "log"
HELP = "Print a show's event log from its database (--since, --json or --csv for programs)."
FIELDS = ("time", "time_s", "level", "kind", "vehicle_id", "job_id", "message")
_DURATION = re.compile(r"^(\d+(?:\.\d+)?)([smhd])$")
_UNIT_S = {"s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0}
_FORMULA_START = ("=", "+", "-", "@", "\t", "\r")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--since",
        metavar="WHEN",
        help="only events from then on: a duration back from now (90s, 15m, 2h, 1d) or a "
        "moment (2026-11-29T14:00, local time unless it names its zone)",
    )
    form = parser.add_mutually_exclusive_group()
    form.add_argument("--json", action="store_true", help="JSON Lines, one event per line")
    form.add_argument("--csv", action="store_true", help="CSV with a header row")


def since_s(when: str, now_s: float) -> float:
    """Unix time of ``--since``; :class:`ValueError` naming what it accepts."""
    if match := _DURATION.match(when.strip()):
        return now_s - float(match.group(1)) * _UNIT_S[match.group(2)]
    try:
        moment = datetime.datetime.fromisoformat(when.strip())
    except ValueError:
        raise ValueError(
            f"--since {when!r}: give a duration (90s, 15m, 2h, 1d) or a moment (2026-11-29T14:00)"
        ) from None
    return moment.timestamp()  # naive: local time


def _iso(time_s: float) -> str:
    moment = datetime.datetime.fromtimestamp(time_s, datetime.UTC)
    return moment.isoformat(timespec="milliseconds").replace("+00:00", "Z")


def _row(event: Event) -> dict[str, object]:
    return {
        "time": _iso(event.time_s),
        "time_s": event.time_s,
        "level": event.level,
        "kind": event.kind,
        "vehicle_id": event.vehicle_id,
        "job_id": event.job_id,
        "message": event.message,
    }


def _cell(value: object) -> object:
    """A CSV cell that no spreadsheet runs as a formula."""
    if isinstance(value, str) and value.startswith(_FORMULA_START):
        return "'" + value
    return value


def _print(events: Iterable[Event], args: argparse.Namespace) -> int:
    """Write the events to stdout in the asked form; returns how many."""
    from tui.safe_text import clean

    count = 0
    out = sys.stdout
    writer = csv.DictWriter(out, fieldnames=FIELDS, lineterminator="\n") if args.csv else None
    if writer is not None:
        writer.writeheader()
    for event in events:
        count += 1
        if writer is not None:
            writer.writerow({k: _cell(v) for k, v in _row(event).items()})
        elif args.json:
            out.write(json.dumps(_row(event), ensure_ascii=False) + "\n")
        else:
            when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(event.time_s))
            where = " ".join(clean(x) for x in (event.vehicle_id, event.job_id) if x)
            out.write(
                f"{when} {event.level:7} {clean(event.kind):18} {where + ' ' if where else ''}"
                f"{clean(event.message, max_chars=2_000)}\n"
            )
    return count


def run(args: argparse.Namespace) -> int:
    from orchestrator.event_log import EventLogError, read_events
    from showfile import ShowError, load_show

    try:
        show = load_show(args.show)
        since = since_s(args.since, time.time()) if args.since else None
    except (ShowError, ValueError) as exc:
        print(f"skyquill log: {exc}", file=sys.stderr)
        return 2
    try:
        count = _print(read_events(show.database_path, since), args)
    except EventLogError as exc:
        print(f"skyquill log: {exc}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # `skyquill log SHOW | head`
        return 0
    if count == 0 and not (args.json or args.csv):
        print(f"skyquill log: no event of show {show.show_id} yet", file=sys.stderr)
    return 0
