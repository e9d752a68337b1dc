"""``skyquill up SHOW.yaml [--headless]``: the whole show on this machine, supervised.

Every process of the show is a child that is restarted when it dies: the Zenoh router
(``skyquill router``, first), ``skyquill sim-mavlink`` when the show says
``mavlink_sim: {enabled: true}``, the orchestrator, one agent per vehicle (with
``fleet_hosts: N``, the simulated vehicles in N ``skyquill fleet`` processes instead) and the
kiosk. Their output goes to ``<database dir>/logs/``; ``up`` writes its pid and theirs to
``<database dir>/up.json``.

Without ``--headless`` the operator console runs in the foreground (when this is a terminal). It
is a viewer: quitting it leaves the show running (``up`` stays in the foreground; Enter reopens the
console), a crash reopens it. The show stops only on purpose: SIGTERM to ``up``, ``skyquill down
SHOW`` from any shell, or Ctrl-C (with vehicles in the air, a second Ctrl-C after ``up`` has
named them: ``cli/interrupt.py``). Each process then gets SIGTERM and its own grace period,
group by group, or all at once after a Ctrl-C that found nothing in the air (then said in
``up.log`` only); a Ctrl-C ends ``up`` with one line and exit status 130, as every command.

A show across several machines (``zenoh.hosts`` in the show file) is started with ``--host NAME``
on each: that host's router, and the orchestrator and kiosk on the ground station, the agents of
its vehicles on a companion host. Only the ground station makes the show's keys; a companion host
needs its identities copied there first. Its run file and logs are ``up-<host>.json`` and
``logs/<host>/``.

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
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from cli.interrupt import StopRequests
from cli.runstate import AdoptedProcess, ProcessRecord, RunFile, command_line
from cli.supervisor import ChildSpec, Supervisor
from cli.viewer import ConsoleViewer, UpOutput, enter_pressed

if TYPE_CHECKING:
    from bus.messages import ShowSnapshot
    from showfile import Show

NAME = "up"
HELP = "Start a whole show: Zenoh router, orchestrator and one agent per vehicle, supervised."
RED, RESET = "\033[1;31m", "\033[0m"
DETACHED = (
    "the console is closed; the show keeps running. Enter: reopen the console; "
    "Ctrl-C here or `skyquill down {show}`: stop the show"
)
FLYING_QUERY_S = 2.0
"""How long a Ctrl-C waits for the orchestrator to say which vehicles fly, wall [s]."""


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
    parser.add_argument(
        "--host", default=None, help="start only this host's processes (a show across machines)"
    )


@dataclass(frozen=True)
class HostPlan:
    """What one ``up`` runs: the whole show, or one host of a show across machines."""

    host: str | None
    """The host (None: a one-machine show)."""
    vehicle_ids: tuple[str, ...]
    """Agents to run here."""
    services: bool
    """Whether the orchestrator (and kiosk, simulated autopilots) run here."""
    log_dir: Path
    """Where the children's logs go."""
    run_file: Path
    """Where the run file is kept."""


def host_plan(show: Show, host: str | None) -> HostPlan:
    """The processes of ``host`` (HostError when the show and ``--host`` do not fit)."""
    from cli.runstate import run_file_path
    from trust.hosts import HostError, check_hosts, host_named

    logs = show.database_path.parent / "logs"
    if host is None:
        if show.zenoh.hosts:
            raise HostError(
                f"show {show.show_id} spans hosts {', '.join(show.zenoh.hosts)}: "
                f"give --host NAME on each"
            )
        vehicles = tuple(v.id for v in show.vehicles)
        return HostPlan(None, vehicles, True, logs, run_file_path(show.database_path))
    check_hosts(show)
    spec = host_named(show, host)
    run_file = run_file_path(show.database_path, host)
    return HostPlan(host, spec.vehicles, spec.services, logs / host, run_file)


def _prepare(args: argparse.Namespace, show: Show) -> tuple[HostPlan, RunFile | None, list[str]]:
    """The host's plan, an earlier run file of it, and the identities issued now."""
    from cli.runstate import RunFileError
    from trust.hosts import host_of
    from trust.settings import check_keys, ensure_show_keys, identities

    plan = host_plan(show, args.host)
    previous = RunFile.load(plan.run_file)
    if previous is not None and previous.up is not None and previous.up.alive():
        raise RunFileError(
            f"show {show.show_id} runs already under skyquill up (pid {previous.up.pid}); "
            f"`skyquill down {args.show}{_host_arg(plan.host)}` stops it"
        )
    if plan.services:
        return plan, previous, ensure_show_keys(show)
    assert plan.host is not None
    check_keys(show, [i for i in identities(show) if host_of(show, i) == plan.host])
    return plan, previous, []


def _viewers(args: argparse.Namespace, show: Show, plan: HostPlan) -> tuple[bool, bool]:
    """Whether to run the console in the foreground, and the kiosk (both on the ground station
    only: a companion host holds no operator's or kiosk's keys)."""
    from cli.supervisor import has_command

    terminal = sys.stdin.isatty() and sys.stdout.isatty()
    tui = plan.services and not args.headless and has_command("tui") and terminal
    enabled = getattr(show.kiosk, "enabled", "kiosk" in show.model_fields_set)
    kiosk = plan.services and not args.no_kiosk and has_command("kiosk") and bool(enabled)
    return tui, kiosk


def _host_arg(host: str | None) -> str:
    return "" if host is None else f" --host {host}"


def run(args: argparse.Namespace) -> int:
    from cli.runstate import RunFileError
    from showfile import ShowError, load_show
    from trust.hosts import HostError

    try:
        show = load_show(args.show)
    except ShowError as exc:
        print(f"skyquill up: {exc}", file=sys.stderr)
        return 2
    if args.time_scale is not None and not args.time_scale > 0.0:
        print("skyquill up: --time-scale must be positive", file=sys.stderr)
        return 2
    if show.security.mode == "none":
        _warn_unsecured(show.show_id)
    try:
        plan, previous, made = _prepare(args, show)
    except (RunFileError, HostError, OSError) as exc:
        print(f"skyquill up: {exc}", file=sys.stderr)
        return 2 if isinstance(exc, HostError) else 1
    tui, kiosk = _viewers(args, show, plan)
    if made:
        print(f"skyquill up: issued keys in {show.keys_dir}: {', '.join(made)}", file=sys.stderr)
    _supervise(args, show, plan, previous, tui=tui, kiosk=kiosk)
    return 0


def _warn_unsecured(show_id: str) -> None:
    """Say on ``up``'s terminal, in red, that the show's bus is open to anyone who reaches it
    (plain text when stderr is not a terminal or ``NO_COLOR`` is set)."""
    line = (
        f"skyquill up: show {show_id} runs with security: none: anyone who reaches its bus "
        f"can command the fleet (loopback tests only)"
    )
    if sys.stderr.isatty() and "NO_COLOR" not in os.environ:
        line = f"{RED}{line}{RESET}"
    print(line, file=sys.stderr)


def _supervise(
    args: argparse.Namespace,
    show: Show,
    plan: HostPlan,
    previous: RunFile | None,
    *,
    tui: bool,
    kiosk: bool,
) -> None:
    """Start (or adopt) the host's children and keep them up until asked to stop; after a
    Ctrl-C, raise ``KeyboardInterrupt`` once they are stopped (``cli/main.py`` ends it)."""
    from cli.fleets import split_fleets
    from cli.supervisor import child_env, show_children, skyquill_argv
    from orchestrator.client import snapshot  # here, not at a Ctrl-C (0.18 s at load 10)

    agents, fleets = split_fleets(show, plan.vehicle_ids)
    specs = show_children(
        args.show,
        agents,
        fleets=fleets,
        time_scale=args.time_scale,
        kiosk=kiosk,
        mavlink_sim=show.mavlink_sim.enabled,
        services=plan.services,
        host=plan.host,
        log_dir=plan.log_dir,
        verbose=args.verbose,
    )
    output = UpOutput(plan.log_dir / "up.log")
    runfile = RunFile(plan.run_file, show.show_id, ProcessRecord.of(os.getpid()))
    supervisor = Supervisor(
        specs,
        env=child_env(),
        say=output.say,
        die_with_supervisor=False,
        on_spawn=lambda name, pid: _record(runfile, name, pid),
    )
    stop = StopRequests(lambda: _flying(show, snapshot), output.say, str(args.show))
    _install_signals(stop, output)
    try:
        _adopt_survivors(supervisor, specs, previous, runfile, output.say)
        supervisor.start()
        runfile.save()
        _announce(
            output, show.show_id, plan.host, [spec.name for spec in specs], plan.log_dir, args.show
        )
        _announce_addresses(output, args.show, kiosk_url(show) if kiosk else None, tui=tui)
        if tui:
            viewer = ConsoleViewer(
                skyquill_argv("tui", str(args.show)),
                env=child_env(),
                say=output.say,
                on_open=lambda pid: _record(runfile, "console", pid),
            )
            _run_with_console(supervisor, viewer, stop, output, str(args.show))
        else:
            supervisor.run_until(stop.due)
    finally:
        output.quiet = stop.grounded  # nothing in the air: a quick stop, in up.log only
        output.say("stopping")
        output.say(supervisor.stop(grounded=stop.grounded).summary())
        runfile.remove()
        output.close()
    if stop.by_ctrl_c:  # one line, exit status 130, no interpreter teardown (cli/main.py)
        raise KeyboardInterrupt


def _announce(
    output: UpOutput, show_id: str, host: str | None, names: list[str], log_dir: Path, show: Path
) -> None:
    """Say what runs, where its logs are and how to stop it."""
    where = "" if host is None else f" (host {host})"
    output.say(f"show {show_id}{where}: {', '.join(names)}")
    output.say(f"logs in {log_dir}/; stop with Ctrl-C or `skyquill down {show}{_host_arg(host)}`")


def kiosk_url(show: Show) -> str:
    """The kiosk's address as a browser on this machine reaches it (a wildcard bind: through
    loopback)."""
    host = show.kiosk.host
    if host in ("0.0.0.0", "::", ""):
        host = "127.0.0.1"
    if ":" in host:
        host = f"[{host}]"
    return f"http://{host}:{show.kiosk.port}/"


def _announce_addresses(output: UpOutput, show: Path, kiosk: str | None, *, tui: bool) -> None:
    """Say where the kiosk answers and how to open the operator console (again)."""
    if kiosk is not None:
        output.say(f"kiosk: {kiosk}")
    here = " (open here now; Enter reopens it once quit)" if tui else ""
    output.say(f"console: `skyquill tui {show}` from any shell{here}")
    output.say(f"summary: `skyquill status {show}`")


def _record(runfile: RunFile, name: str, pid: int) -> None:
    record = ProcessRecord.of(pid)
    if record is not None:
        runfile.children[name] = record
        runfile.save()


def _flying(show: Show, snapshot: Callable[..., ShowSnapshot]) -> list[str] | None:
    """The show's vehicles in the air, as the orchestrator sees them through ``snapshot``
    (``orchestrator.client.snapshot``); None: it does not answer, or this host holds no operator
    certificate."""
    from bus.messages import AIRBORNE_STATES

    try:
        vehicles = snapshot(show, timeout_s=FLYING_QUERY_S).vehicles
    except Exception:  # no answer, no keys here: the question says it cannot tell
        return None
    return [v.vehicle_id for v in vehicles if v.state in AIRBORNE_STATES]


def _install_signals(stop: StopRequests, output: UpOutput) -> None:
    """SIGTERM stops the show, Ctrl-C too unless vehicles fly (``cli/interrupt.py``); SIGHUP
    (the terminal went away) only silences ``up``."""
    signal.signal(signal.SIGINT, lambda _signum, _frame: stop.interrupt())
    signal.signal(signal.SIGTERM, lambda _signum, _frame: stop.terminate())

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
    stop: StopRequests,
    output: UpOutput,
    show: str,
) -> None:
    """Supervise with the console in the foreground until ``stop``; the console never stops it."""
    output.quiet = True
    viewer.open()
    try:
        while not stop.due():
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
