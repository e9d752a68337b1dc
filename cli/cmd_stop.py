"""``skyquill down SHOW.yaml`` (also ``skyquill stop``): stop a show that ``skyquill up`` runs.

It reads ``<database dir>/up.json``. While that ``up`` runs, it sends it SIGTERM and waits: ``up``
stops its processes as on Ctrl-C. When ``up`` is gone (killed) but its processes still run, it
stops them itself in the same order: agents and kiosk, the orchestrator, simulated autopilots,
the router last; each gets SIGTERM and its own grace period, and only one that outlives its own
grace gets SIGKILL. ``--host NAME`` stops one host of a show across machines (the processes in
its ``up-<host>.json``).
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from cli.cmd_up import HostPlan
    from cli.runstate import RunFile
    from showfile import Show

NAME = "down"
ALIASES = "stop"
HELP = "Stop a show started by skyquill up (cleanly: SIGTERM, a grace period per process)."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--timeout", type=float, default=60.0, help="how long to wait for the show to stop [s]"
    )
    parser.add_argument("--host", default=None, help="the host to stop (a show across machines)")


def run(args: argparse.Namespace) -> int:
    from cli.cmd_up import host_plan
    from cli.runstate import RunFile, RunFileError
    from showfile import ShowError, load_show
    from trust.hosts import HostError

    try:
        show = load_show(args.show)
        plan = host_plan(show, args.host)
        runfile = RunFile.load(plan.run_file)
    except (ShowError, RunFileError, HostError) as exc:
        print(f"skyquill down: {exc}", file=sys.stderr)
        return 2
    if runfile is None:
        print(f"skyquill down: show {show.show_id} is not running here", file=sys.stderr)
        return 1
    up = runfile.up
    if up is not None and up.alive():
        os.kill(up.pid, signal.SIGTERM)
        deadline = time.monotonic() + args.timeout
        while up.alive():
            if time.monotonic() > deadline:
                print(
                    f"skyquill down: skyquill up (pid {up.pid}) still runs after "
                    f"{args.timeout:.0f} s",
                    file=sys.stderr,
                )
                return 1
            time.sleep(0.1)
        print(f"skyquill down: show {show.show_id} stopped (skyquill up pid {up.pid})")
        return 0
    return _stop_orphans(args.show, show, runfile, plan)


def _stop_orphans(show_path: Path, show: Show, runfile: RunFile, plan: HostPlan) -> int:
    """``up`` is gone: stop the processes it left, as it would have."""
    from cli.fleets import split_fleets
    from cli.runstate import AdoptedProcess
    from cli.supervisor import ChildSpec, Supervisor, show_children

    agents, fleets = split_fleets(show, plan.vehicle_ids)
    known = {
        spec.name: spec
        for spec in show_children(
            show_path,
            agents,
            fleets=fleets,
            kiosk=True,
            mavlink_sim=True,
            services=plan.services,
            host=plan.host,
        )
    }
    running = {name: record for name, record in runfile.children.items() if record.alive()}
    specs = [known.get(name) or ChildSpec(name, ()) for name in running]
    supervisor = Supervisor(specs, say=lambda line: print(f"skyquill down: {line}"))
    for name, record in running.items():
        supervisor.adopt(name, AdoptedProcess(record))
    print(f"skyquill down: {supervisor.stop().summary()}")
    runfile.remove()
    names = ", ".join(running) or "nothing was left running"
    print(f"skyquill down: show {show.show_id} stopped ({names})")
    return 0
