"""``skyquill status SHOW.yaml [--json]``: jobs and vehicles as the orchestrator sees them.

A one-off command, kept light: it reads only the bus part of the show file
(:mod:`showfile.bus_view`; the full loader judges a file that view does not vouch for) and asks
through :mod:`orchestrator.client`: neither pydantic nor numpy is loaded
(tests/test_cli_imports.py).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from bus.messages import ShowSnapshot
    from showfile.bus_view import ShowBus

NAME = "status"
HELP = "Show the jobs and vehicles of a running show (--json for programs)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--json",
        action="store_true",
        help="print JSON: jobs (older finished ones left out), vehicles, job_counts (all jobs), "
        "open alerts",
    )
    parser.add_argument("--timeout", type=float, default=5.0, help="seconds to wait for a reply")


def _show_bus(path: Path) -> ShowBus:
    """The bus part of the show file; the full loader's verdict when the light view gives none
    (ShowError naming file, line and field)."""
    from showfile.bus_view import read_bus_view

    view = read_bus_view(path)
    if view is not None:
        return view
    from showfile import load_show

    return load_show(path)


def _snapshot(path: Path, timeout_s: float) -> ShowSnapshot:
    """The orchestrator's current view; BusError saying what is not running, with the way
    out, when nobody answers."""
    from bus.rpc import NoReplyError
    from bus.session import SessionOpenError
    from orchestrator.client import snapshot

    bus = _show_bus(path)
    zenoh = bus.zenoh
    where = ", ".join(zenoh.connect or zenoh.router_listen[:1])
    try:
        return snapshot(bus, timeout_s=timeout_s)
    except SessionOpenError:
        raise SessionOpenError(
            f"no show running at {where}: start it with `skyquill up {path}`"
        ) from None
    except NoReplyError:
        raise NoReplyError(
            f"the router at {where} answers, but no orchestrator of show {bus.show_id} did "
            f"within {timeout_s:g} s: starting, or stopped? `skyquill up {path}` starts it"
        ) from None


def vehicle_note(job_id: str | None, message: str) -> str:
    """A vehicle's message without the job it names again (``job j1 written``: ``written``)."""
    if job_id and message.startswith(f"job {job_id}"):
        return message.removeprefix(f"job {job_id}").strip()
    return message


def run(args: argparse.Namespace) -> int:
    import msgspec

    from bus.rpc import NoReplyError, RemoteError
    from bus.session import SessionOpenError
    from showfile.errors import ShowError

    if not args.timeout > 0.0:
        print(f"skyquill status: --timeout must be above 0 s, not {args.timeout:g}",
              file=sys.stderr)  # fmt: skip
        return 2
    try:
        snap = _snapshot(args.show, args.timeout)
    except (ShowError, SessionOpenError, NoReplyError, RemoteError) as exc:
        print(f"skyquill status: {exc}", file=sys.stderr)
        return 2
    if args.json:
        data = msgspec.to_builtins(snap)
        print(
            json.dumps(
                {
                    "jobs": data["jobs"],
                    "vehicles": data["vehicles"],
                    "job_counts": snap.job_counts,
                    "alerts": data["alerts"],
                    "queue_paused": snap.queue_paused,
                    "time_s": snap.time_s,
                },
                ensure_ascii=False,
            )
        )
        return 0
    paused = " (queue paused)" if snap.queue_paused else ""
    print(f"show {snap.show_id}{paused}")
    counts = ", ".join(f"{n} {state}" for state, n in snap.job_counts.items())
    print(f"  jobs: {sum(snap.job_counts.values())} ({counts or 'none'})")
    for v in snap.vehicles:
        alive = "up" if v.alive else "down"
        note = vehicle_note(v.job_id, v.message)
        line = (
            f"  {v.vehicle_id:8} {alive:4} {v.state:11} board {v.board_id or '-':4} "
            f"job {v.job_id or '-'} {note}"
        )
        print(line.rstrip())
    for j in snap.jobs:
        where = f"#{j.queue_position}" if j.queue_position else (j.vehicle_id or "")
        eta = f" eta {j.eta_s:.0f} s" if j.eta_s is not None else ""
        print(f"  {j.job_id} {j.state:17} {where:6} {j.label}{eta}")
    for alert in snap.alerts:  # open: their cause lasts, however long ago they were raised
        raised = time.strftime("%H:%M:%S", time.localtime(alert.time_s))
        print(f"  alert {raised} {alert.kind}: {alert.message}")
    return 0
