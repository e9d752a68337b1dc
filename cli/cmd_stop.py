"""``skyquill down SHOW.yaml`` (also ``skyquill stop``): land, then stop a show that
``skyquill up`` runs.

First every vehicle in the air lands (``cli/landing.py``: through the orchestrator's
``land_all``, which takes their jobs back and holds them, or straight to each vehicle when the
orchestrator does not answer), up to ``--land-timeout``, one line per vehicle. A vehicle that has
not said it is down by then keeps its agent and its link: nothing is stopped and the command
fails, saying how to go on. ``--now`` skips the landing: the agents stop at once
(``vehicle_agent/stop_signals.py``: without it an agent still in the air when it gets SIGTERM
lands first, whoever sent it).

Then, with ``<database dir>/up.json``: while that ``up`` runs, it sends it SIGTERM and waits;
``up`` stops its processes as on Ctrl-C. When ``up`` is gone (killed) but its processes still
run, it stops them itself in the same order: agents and kiosk, the orchestrator, simulated
autopilots, the router last; each gets SIGTERM and its own grace period, and only one that
outlives its own grace gets SIGKILL. ``--host NAME`` stops one host of a show across machines
(the processes in its ``up-<host>.json``).
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
HELP = "Land every vehicle in the air, then stop a show started by skyquill up."
LAND_TIMEOUT_S = 60.0
"""Default wait for the vehicles to land, wall [s]: from mid-character the return and the descent
took 7.6-14 s of flight (``vehicle_agent/stop_signals.py``, ``LAND_LIMIT_S``); four times that
for a larger venue, a loaded machine or a slow autopilot."""


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument(
        "--timeout", type=float, default=60.0, help="how long to wait for the show to stop [s]"
    )
    parser.add_argument("--host", default=None, help="the host to stop (a show across machines)")
    parser.add_argument(
        "--land-timeout",
        type=float,
        default=LAND_TIMEOUT_S,
        help=f"how long the vehicles in the air may take to land [s] ({LAND_TIMEOUT_S:.0f})",
    )
    parser.add_argument(
        "--now", action="store_true", help="stop at once, without landing the vehicles in the air"
    )


def run(args: argparse.Namespace) -> int:
    from cli.cmd_up import host_plan
    from cli.runstate import RunFile, RunFileError
    from showfile import ShowError, load_show
    from trust.hosts import HostError

    if not args.land_timeout > 0.0:
        print("skyquill down: --land-timeout must be positive", file=sys.stderr)
        return 2
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
    if args.now:
        _agents_now(runfile)
    elif not _landed(args, show, plan):
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


def _landed(args: argparse.Namespace, show: Show, plan: HostPlan) -> bool:
    """Land the host's vehicles in the air; whether the show may be stopped (all said so)."""
    from cli.landing import land_before_stop

    landed = land_before_stop(
        show,
        plan.vehicle_ids,
        whole_show=args.host is None,
        timeout_s=args.land_timeout,
        say=lambda line: print(f"skyquill down: {line}", flush=True),
    )
    if landed.not_down:
        names = ", ".join(landed.not_down)
        print(
            f"skyquill down: {names} may still be in the air: the show keeps running, so that "
            f"{'its link stays' if len(landed.not_down) == 1 else 'their links stay'} up. Land "
            f"{'it' if len(landed.not_down) == 1 else 'them'} (console, or the pilot's radio), "
            f"then `skyquill down {args.show}` again; `skyquill down {args.show} --now` stops "
            "without landing",
            file=sys.stderr,
        )
        return False
    if landed.held:
        one = len(landed.flying) == 1
        paused = " and the queue paused" if args.host is None else ""
        resume = ", then `resume`" if args.host is None else ""
        print(
            f"skyquill down: {', '.join(landed.flying)} {'is' if one else 'are'} held{paused}: "
            f"after the next skyquill up, `skyquill command {args.show} release-all`{resume}"
        )
    return True


def _agents_now(runfile: RunFile) -> None:
    """Tell each agent and fleet host to stop at once, without landing (before ``up`` stops
    them: a SIGTERM alone would have them land first)."""
    from vehicle_agent.stop_signals import NOW_SIGNAL

    for name, record in runfile.children.items():
        if name.startswith(("agent ", "fleet ")) and record.alive():
            os.kill(record.pid, NOW_SIGNAL)


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
