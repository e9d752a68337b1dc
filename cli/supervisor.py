"""Supervise the processes of a show: start them, restart the ones that die, stop them all.

:class:`RestartPolicy` decides (pure); :class:`Supervisor` carries it out with ``subprocess``.
Children run in their own session, so a Ctrl-C in the terminal reaches only the supervisor, which
then stops them group by group (``ChildSpec.stop_group``: agents and kiosk, then the
orchestrator, then simulated autopilots, then the router; all groups together once no vehicle
is in the air, :meth:`Supervisor.stop`): each child of a group gets SIGTERM and
its own grace period, and only a child that outlives its own grace gets SIGKILL. The grace is
measured against the child's progress: past it, a child still using CPU or waiting for one
is given up to ``stop_limit_s``; one that sits idle (stuck) is killed (``cli/stopping.py``).

An agent that gets SIGTERM with its vehicle in the air lands it before it stops
(``vehicle_agent/stop_signals.py``); a stop in a hurry (:meth:`Supervisor.hurry`: Ctrl-C in the
demo, ``skyquill down --now``) first gives those children their signal to stop without landing
(``ChildSpec.lands_on_stop``), then stops every group at once.

Whether children outlive the supervisor is a choice (``die_with_supervisor``): ``ShowRun`` (the
demo, tests) has them get SIGTERM when it dies (``PR_SET_PDEATHSIG``), so nothing is left behind;
``skyquill up`` lets them run on, so that vehicles in the air never depend on the supervisor
process, and a restarted ``up`` adopts them (:meth:`Supervisor.adopt`, ``cli/runstate.py``).
"""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from cli.stopping import ProcessHandle, Stopping, StopReport, describe_end, stop_group
from vehicle_agent.stop_signals import NOW_SIGNAL

PR_SET_PDEATHSIG = 1


@dataclass(frozen=True)
class RestartPolicy:
    """Exponential backoff between restarts, forgotten once a process has run long enough."""

    initial_delay_s: float = 0.5
    """Wait in [s] before the first restart."""
    factor: float = 2.0
    """Each further restart waits this much longer..."""
    max_delay_s: float = 10.0
    """...up to this many [s]."""
    stable_after_s: float = 30.0
    """A process that ran this long in [s] before dying starts over at ``initial_delay_s``."""

    def delay_s(self, previous_delay_s: float | None, ran_for_s: float) -> float:
        """How long to wait before restarting a process that died after ``ran_for_s``."""
        if previous_delay_s is None or ran_for_s >= self.stable_after_s:
            return self.initial_delay_s
        return min(self.max_delay_s, previous_delay_s * self.factor)


ROUTER_RESTART = RestartPolicy(
    initial_delay_s=0.1, factor=2.0, max_delay_s=1.0, stable_after_s=10.0
)
"""The router comes back fast: every client is waiting to reconnect to it."""


@dataclass(frozen=True)
class ChildSpec:
    """One process of the show."""

    name: str
    """Short name for messages, e.g. ``orchestrator`` or ``agent uav2``."""
    argv: tuple[str, ...]
    """Command line."""
    log_path: Path | None = None
    """Where its stdout and stderr go (None: the supervisor's own stderr)."""
    restart: RestartPolicy | None = None
    """Its own restart backoff (None: the supervisor's)."""
    stop_grace_s: float = 5.0
    """How long in [s] it may take to stop after SIGTERM before it alone gets SIGKILL, unless it
    is still working on it (using CPU)."""
    stop_limit_s: float = 60.0
    """How long in [s] a child still using CPU may take to stop before it gets SIGKILL."""
    stop_group: int = 0
    """Lower groups are stopped first; the children of one group are stopped together."""
    lands_on_stop: bool = False
    """Whether it lands its vehicle on SIGTERM before it stops (an agent): a hurried stop sends
    it ``NOW_SIGNAL`` first (``vehicle_agent/stop_signals.py``)."""


@dataclass
class _Child:
    spec: ChildSpec
    process: ProcessHandle | None = None
    started_s: float = 0.0
    delay_s: float | None = None
    restart_at_s: float | None = None
    restarts: int = 0
    log: IO[bytes] | None = field(default=None, repr=False)


def _die_with_parent() -> None:  # pragma: no cover - runs in the child before exec
    try:
        libc = ctypes.CDLL("libc.so.6", use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    except OSError:
        pass


def skyquill_argv(*args: str) -> tuple[str, ...]:
    """Command line of a ``skyquill`` subcommand run by this Python interpreter."""
    return (sys.executable, "-m", "cli.main", *args)


class Supervisor:
    """Starts children, restarts those that die (saying so), stops all of them on request."""

    def __init__(
        self,
        specs: Sequence[ChildSpec],
        *,
        policy: RestartPolicy | None = None,
        env: Mapping[str, str] | None = None,
        say: Callable[[str], None] | None = None,
        clock: Callable[[], float] = time.monotonic,
        die_with_supervisor: bool = True,
        on_spawn: Callable[[str, int], None] | None = None,
    ) -> None:
        self.policy = policy or RestartPolicy()
        self._children = {spec.name: _Child(spec) for spec in specs}
        self._env = dict(env) if env is not None else None
        self._say = say or (lambda line: print(f"skyquill up: {line}", file=sys.stderr, flush=True))
        self._clock = clock
        self._die_with_supervisor = die_with_supervisor
        self._on_spawn = on_spawn
        self.stopping = False
        self.hurried = False
        """Whether stops are hurried (:meth:`hurry`)."""
        self._told_now: set[int] = set()
        """Pids already sent ``NOW_SIGNAL``: a stop after a hurry tells only the children started
        since (told twice, an agent handled its hurry twice; a fresh clone's CI)."""

    @property
    def names(self) -> list[str]:
        """The children's names, in start order."""
        return list(self._children)

    def adopt(self, name: str, process: ProcessHandle) -> None:
        """Supervise ``process``, already running, as the child ``name`` (not started again)."""
        child = self._children[name]
        if child.process is not None:
            raise ValueError(f"{name} is running already")
        child.process = process
        child.started_s = self._clock()

    def start(self) -> None:
        """Start every child that is not running."""
        for child in self._children.values():
            if child.process is None:
                self._spawn(child)

    def _spawn(self, child: _Child) -> None:
        spec = child.spec
        if spec.log_path is not None and child.log is None:
            spec.log_path.parent.mkdir(parents=True, exist_ok=True)
            child.log = spec.log_path.open("ab")
        out = child.log if child.log is not None else sys.stderr
        linux = sys.platform.startswith("linux")
        preexec = _die_with_parent if linux and self._die_with_supervisor else None
        child.process = subprocess.Popen(
            spec.argv,
            env=self._env,
            stdin=subprocess.DEVNULL,
            stdout=out,
            stderr=out,
            start_new_session=True,
            preexec_fn=preexec,
        )
        child.started_s = self._clock()
        child.restart_at_s = None
        if self._on_spawn is not None:
            self._on_spawn(spec.name, child.process.pid)

    def pid(self, name: str) -> int | None:
        """Process id of a running child."""
        process = self._children[name].process
        return None if process is None else process.pid

    def restarts(self, name: str) -> int:
        """How many times a child was restarted."""
        return self._children[name].restarts

    def poll(self) -> None:
        """Notice children that died and restart those whose backoff is over."""
        now = self._clock()
        for name, child in self._children.items():
            process = child.process
            if process is not None and process.poll() is not None:
                child.process = None
                if self.stopping:
                    continue
                ran_for = now - child.started_s
                policy = child.spec.restart or self.policy
                child.delay_s = policy.delay_s(child.delay_s, ran_for)
                child.restart_at_s = now + child.delay_s
                self._say(
                    f"{name} exited ({describe_end(process)}) after "
                    f"{ran_for:.1f} s; restarting in {child.delay_s:.1f} s"
                )
            due = child.restart_at_s is not None and now >= child.restart_at_s
            if child.process is None and due and not self.stopping:
                child.restarts += 1
                self._spawn(child)
                self._say(f"{name} restarted (pid {self.pid(name)})")

    def hurry(self) -> None:
        """From now on (a stop under way included) stop without landing and every group at
        once: each child that lands on SIGTERM gets ``NOW_SIGNAL`` at once. Safe to call from a
        signal handler (it only signals and sets flags)."""
        self.hurried = self.stopping = True
        for child in list(self._children.values()):
            process = child.process
            if not child.spec.lands_on_stop or process is None or process.poll() is not None:
                continue
            if process.pid not in self._told_now:
                self._told_now.add(process.pid)
                process.send_signal(NOW_SIGNAL)

    def stop(self, grace_s: float | None = None, *, grounded: bool = False) -> StopReport:
        """Stop every child, group by group (``ChildSpec.stop_group``), or all at once when
        hurried or ``grounded``: SIGTERM, then wait for each child its own grace (``grace_s`` if
        given, else its ``stop_grace_s``), then SIGKILL only the children that outlived theirs.
        Returns how long each took.

        ``grounded``: the caller has just seen no vehicle in the air (``cli/interrupt.py``), so
        no agent has a landing to fly that would need the processes of later groups (its
        simulated autopilot, the orchestrator that hears it land, the router between them): the
        groups are stopped together, the stop taking its slowest child's time rather than the
        sum of every group's (1.9 s of a 2.85 s Ctrl-C at load 13.8, issue 34). Unlike a hurry,
        no agent is told to skip its landing: one that finds itself in the air still lands."""
        self.stopping = True
        if self.hurried:
            self.hurry()  # children started since the hurry was asked
        started = time.monotonic()
        report = StopReport()
        groups = sorted({c.spec.stop_group for c in self._children.values()})
        for group in [None] if self.hurried or grounded else groups:
            members = [c for c in self._children.values() if group in (None, c.spec.stop_group)]
            stopping = [
                Stopping.of(
                    c.spec.name, c.process, c.spec.stop_grace_s, c.spec.stop_limit_s, grace_s
                )
                for c in members
                if c.process is not None
            ]
            stop_group(stopping, report, self._say)
        for child in self._children.values():
            if child.log is not None:
                child.log.close()
                child.log = None
        report.total_s = time.monotonic() - started
        return report

    def run_until(self, done: Callable[[], bool], period_s: float = 0.1) -> None:
        """Poll until ``done()`` is true."""
        while not done():
            self.poll()
            time.sleep(period_s)


def install_stop_signals(stop: Callable[[], None]) -> None:
    """Call ``stop`` on SIGINT and SIGTERM (main thread only)."""
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda _signum, _frame: stop())


def child_env() -> dict[str, str]:
    """The environment for children: ours, unbuffered, with the checkout importable."""
    env = dict(os.environ)
    env["PYTHONUNBUFFERED"] = "1"
    root = str(Path(__file__).resolve().parent.parent)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH", "")) if p)
    return env


# --- the processes of a show --------------------------------------------------------------------


def has_command(name: str) -> bool:
    """Whether ``skyquill <name>`` exists in this checkout (``cli/cmd_<name>.py``)."""
    return (Path(__file__).resolve().parent / f"cmd_{name}.py").is_file()


FLEET_GRACE_S = 8.0
"""A fleet host's grace to stop, in [s], as an agent's..."""
FLEET_GRACE_PER_VEHICLE_S = 0.05
"""...plus this much per vehicle it carries (each closes its session; pictures being drawn)."""


def fleet_stop_grace_s(vehicles: int) -> float:
    """How long in [s] a fleet host of ``vehicles`` may take to stop before SIGKILL."""
    return FLEET_GRACE_S + FLEET_GRACE_PER_VEHICLE_S * vehicles


def show_children(
    show_path: Path,
    vehicle_ids: Sequence[str],
    *,
    time_scale: float | None = None,
    kiosk: bool = False,
    mavlink_sim: bool = False,
    router: bool = True,
    services: bool = True,
    host: str | None = None,
    log_dir: Path | None = None,
    verbose: bool = False,
    fleets: Sequence[Sequence[str]] = (),
) -> list[ChildSpec]:
    """The show's Zenoh router (``skyquill router``), optionally the simulated MAVLink vehicles
    (``skyquill sim-mavlink``), the orchestrator, one agent per vehicle of ``vehicle_ids``, one
    fleet host per group of ``fleets`` (``cli/fleets.py``), then optionally the kiosk; stopped
    agents, fleet hosts and kiosk first, the router last. ``host``: one host of a show across
    machines (its router); ``services``: whether the orchestrator (and kiosk, sim-mavlink) run
    here, as on the ground station."""
    show = str(show_path)

    def log(name: str) -> Path | None:
        return None if log_dir is None else log_dir / f"{name}.log"

    specs = []
    if router:
        router_argv = skyquill_argv("router", show, *(() if host is None else ("--host", host)))
        specs.append(ChildSpec("router", router_argv, log("router"), ROUTER_RESTART, stop_group=3))
    if mavlink_sim and services:
        argv = ["sim-mavlink", show]
        if time_scale is not None:
            argv += ["--time-scale", repr(time_scale)]
        specs.append(
            ChildSpec("sim-mavlink", skyquill_argv(*argv), log("sim-mavlink"), stop_group=2)
        )
    if services:
        orchestrator = skyquill_argv("orchestrator", show)
        specs.append(ChildSpec("orchestrator", orchestrator, log("orchestrator"), stop_group=1))
    for vehicle_id in vehicle_ids:
        argv = ["agent", show, "--vehicle", vehicle_id]
        if time_scale is not None:
            argv += ["--time-scale", repr(time_scale)]
        if verbose:
            argv.append("--verbose")
        spec = ChildSpec(
            f"agent {vehicle_id}",
            skyquill_argv(*argv),
            log(vehicle_id),
            stop_grace_s=8.0,
            lands_on_stop=True,
        )
        specs.append(spec)
    for number, group in enumerate(fleets, start=1):
        argv = ["fleet", show, "--vehicles", ",".join(group)]
        if time_scale is not None:
            argv += ["--time-scale", repr(time_scale)]
        if verbose:
            argv.append("--verbose")
        grace_s = fleet_stop_grace_s(len(group))
        name = f"fleet {number}"
        log_path = log(f"fleet{number}")
        specs.append(
            ChildSpec(name, skyquill_argv(*argv), log_path, None, grace_s, lands_on_stop=True)
        )
    if kiosk and services:
        specs.append(ChildSpec("kiosk", skyquill_argv("kiosk", show), log("kiosk")))
    return specs
