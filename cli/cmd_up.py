"""``skyquill up SHOW.yaml [--headless]``: the whole show on this machine, supervised.

Every process of the show is a child that is restarted when it dies: the Zenoh router
(``skyquill router``, first), ``skyquill sim-mavlink`` when the show says
``mavlink_sim: {enabled: true}``, the orchestrator, one agent per vehicle and the kiosk. Their
output goes to ``<database dir>/logs/``; ``up`` writes its pid and theirs to
``<database dir>/up.json``.

Without ``--headless`` the operator console runs in the foreground (when this is a terminal). It
is a viewer: quitting it leaves the show running (``up`` stays in the foreground; Enter reopens the
console), a crash reopens it. The show stops only on purpose: Ctrl-C or SIGTERM to ``up``, or
``skyquill down SHOW`` from any shell. Each process then gets SIGTERM and its own grace period.

The children outlive ``up`` itself: a killed ``up``, or a hung-up terminal, never takes the
router or a vehicle down. Started again, ``up`` adopts the processes that still run (same pid,
same start time, same command line) and starts the missing ones; ``skyquill down`` stops them.
"""

from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

from cli.runstate import AdoptedProcess, ProcessRecord, RunFile, command_line
from cli.supervisor import ChildSpec, Supervisor
from cli.viewer import ConsoleViewer, UpOutput, enter_pressed

NAME = "up"
HELP = "Start a whole show: Zenoh router, orchestrator and one agent per vehicle, supervised."
DETACHED = (
    "the console is closed; the show keeps running. Enter: reopen the console; "
    "Ctrl-C here or `skyquill down {show}`: stop the show"
)


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
    from cli.runstate import RunFileError, run_file_path
    from cli.supervisor import child_env, has_command, show_children, skyquill_argv
    from showfile import ShowError, load_show
    from trust.settings import ensure_show_keys

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
    log_dir = show.database_path.parent / "logs"
    try:
        previous = RunFile.load(run_file_path(show.database_path))
        if previous is not None and previous.up is not None and previous.up.alive():
            raise RunFileError(
                f"show {show.show_id} runs already under skyquill up (pid {previous.up.pid}); "
                f"`skyquill down {args.show}` stops it"
            )
        made = ensure_show_keys(show)
    except (RunFileError, OSError) as exc:
        print(f"skyquill up: {exc}", file=sys.stderr)
        return 1
    if made:
        print(f"skyquill up: issued keys in {show.keys_dir}: {', '.join(made)}", file=sys.stderr)
    specs = show_children(
        args.show,
        [v.id for v in show.vehicles],
        time_scale=args.time_scale,
        kiosk=kiosk,
        mavlink_sim=show.mavlink_sim.enabled,
        log_dir=log_dir,
        verbose=args.verbose,
    )
    output = UpOutput(log_dir / "up.log")
    runfile = RunFile(
        run_file_path(show.database_path), show.show_id, ProcessRecord.of(os.getpid())
    )
    supervisor = Supervisor(
        specs,
        env=child_env(),
        say=output.say,
        die_with_supervisor=False,
        on_spawn=lambda name, pid: _record(runfile, name, pid),
    )
    stop = threading.Event()
    _install_signals(stop, output)
    try:
        _adopt_survivors(supervisor, specs, previous, runfile, output.say)
        supervisor.start()
        runfile.save()
        names = ", ".join(spec.name for spec in specs)
        output.say(f"show {show.show_id} on {', '.join(show.zenoh.router_listen)}: {names}")
        output.say(f"logs in {log_dir}/; stop with Ctrl-C or `skyquill down {args.show}`")
        if tui:
            viewer = ConsoleViewer(
                skyquill_argv("tui", str(args.show)),
                env=child_env(),
                say=output.say,
                on_open=lambda pid: _record(runfile, "console", pid),
            )
            _run_with_console(supervisor, viewer, stop, output, str(args.show))
        else:
            supervisor.run_until(stop.is_set)
    finally:
        output.quiet = False
        output.say("stopping")
        supervisor.stop()
        runfile.remove()
        output.close()
    return 0


def _record(runfile: RunFile, name: str, pid: int) -> None:
    record = ProcessRecord.of(pid)
    if record is not None:
        runfile.children[name] = record
        runfile.save()


def _install_signals(stop: threading.Event, output: UpOutput) -> None:
    """SIGINT/SIGTERM stop the show; SIGHUP (the terminal went away) only silences ``up``."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda _signum, _frame: stop.set())

    def hung_up(_signum: int, _frame: object) -> None:
        output.hung_up = True
        output.say("the terminal hung up; the show keeps running (`skyquill down` stops it)")

    signal.signal(signal.SIGHUP, hung_up)


def _adopt_survivors(
    supervisor: Supervisor,
    specs: list[ChildSpec],
    previous: RunFile | None,
    runfile: RunFile,
    say: Callable[[str], None],
) -> None:
    """Adopt the processes an earlier ``up`` of this show left running; stop those that do not
    belong to this set-up any more (another command line, or no longer wanted)."""
    if previous is None:
        return
    wanted = {spec.name: spec for spec in specs}
    for name, record in previous.children.items():
        if not record.alive():
            continue
        spec = wanted.get(name)
        if spec is not None and command_line(record.pid) == spec.argv:
            supervisor.adopt(name, AdoptedProcess(record))
            runfile.children[name] = record
            say(f"adopted {name} (pid {record.pid}), still running from an earlier skyquill up")
            continue
        say(f"stopping {name} (pid {record.pid}), left by an earlier skyquill up")
        stray = AdoptedProcess(record)
        stray.terminate()
        try:
            stray.wait(timeout=spec.stop_grace_s if spec is not None else 5.0)
        except subprocess.TimeoutExpired:
            stray.kill()


def _run_with_console(
    supervisor: Supervisor,
    viewer: ConsoleViewer,
    stop: threading.Event,
    output: UpOutput,
    show: str,
) -> None:
    """Supervise with the console in the foreground until ``stop``; the console never stops it."""
    output.quiet = True
    viewer.open()
    try:
        while not stop.is_set():
            supervisor.poll()
            outcome = viewer.poll()
            if outcome in ("quit", "given_up"):
                output.quiet = False
                output.say(DETACHED.format(show=show))
            elif not viewer.open_now and not output.hung_up and enter_pressed():
                output.quiet = True
                viewer.open()
            if output.hung_up and viewer.open_now:
                viewer.close()
            time.sleep(0.1)
    finally:
        viewer.close()
