"""``skyquill up SHOW.yaml [--headless]``: the whole show on this machine, supervised.

A Zenoh router runs in this process (listening on the show's ``zenoh.router_listen``); the
orchestrator and one agent per vehicle (plus the kiosk, and ``skyquill sim-mavlink`` when the show
says ``mavlink_sim: {enabled: true}``) run as child processes that are restarted when they die.
Without ``--headless`` the operator console runs in the foreground (when installed and this is a
terminal; children then log to ``out/<show>/logs/``); quitting it, Ctrl-C or SIGTERM stops all.
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import threading
from pathlib import Path

NAME = "up"
HELP = "Start a whole show: Zenoh router, orchestrator and one agent per vehicle, supervised."


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("show", type=Path, help="show file (YAML)")
    parser.add_argument("--headless", action="store_true", help="no operator console")
    parser.add_argument("--no-kiosk", action="store_true", help="do not start the web kiosk")
    parser.add_argument(
        "--time-scale",
        type=float,
        default=None,
        help="simulated seconds per wall second for sim vehicles (default: the show's)",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help="agents log every command")


def run(args: argparse.Namespace) -> int:
    from bus.session import SessionOpenError, open_session
    from cli.supervisor import (
        Supervisor,
        child_env,
        has_command,
        install_stop_signals,
        show_children,
        skyquill_argv,
    )
    from showfile import ShowError, load_show

    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill up: {exc}", file=sys.stderr)
        return 2
    if args.time_scale is not None and not args.time_scale > 0.0:
        print("skyquill up: --time-scale must be positive", file=sys.stderr)
        return 2
    terminal = sys.stdin.isatty() and sys.stdout.isatty()
    tui = not args.headless and has_command("tui") and terminal
    enabled = getattr(show.kiosk, "enabled", "kiosk" in show.model_fields_set)
    kiosk = not args.no_kiosk and has_command("kiosk") and bool(enabled)
    log_dir = Path("out") / show.show_id / "logs" if tui else None
    specs = show_children(
        args.show,
        [v.id for v in show.vehicles],
        time_scale=args.time_scale,
        kiosk=kiosk,
        mavlink_sim=show.mavlink_sim.enabled,
        log_dir=log_dir,
        verbose=args.verbose,
    )
    stop = threading.Event()
    install_stop_signals(stop.set)
    try:
        router = open_session(show.zenoh, role="router")
    except SessionOpenError as exc:
        print(f"skyquill up: {exc}", file=sys.stderr)
        return 1
    with router:
        supervisor = Supervisor(specs, env=child_env())
        supervisor.start()
        names = ", ".join(spec.name for spec in specs)
        print(
            f"skyquill up: show {show.show_id} on {', '.join(show.zenoh.router_listen)}: {names}",
            file=sys.stderr,
            flush=True,
        )
        if log_dir is not None:
            print(f"skyquill up: logs in {log_dir}/", file=sys.stderr, flush=True)
        if tui:
            console = subprocess.Popen(skyquill_argv("tui", str(args.show)), env=child_env())
            supervisor.run_until(lambda: stop.is_set() or console.poll() is not None)
            if console.poll() is None:
                console.terminate()
                console.wait()
        else:
            supervisor.run_until(stop.is_set)
        print("skyquill up: stopping", file=sys.stderr, flush=True)
        supervisor.stop()
    return 0
