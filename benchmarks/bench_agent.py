"""Light agents: what an idle vehicle agent costs, and how steady its control loop stays while a
job is planned.

    nice -n 15 .venv/bin/python benchmarks/bench_agent.py [--vehicles 10] [--idle-s 20]
        [--peer-commit REV | --peer-tree DIR] [--skip-fleet] [--skip-loop]

Two parts, each printed beside a peer measured in the same run:

- **idle fleet**: a real ``skyquill up --headless`` of the Airshow show widened to ``--vehicles``
  sim vehicles (``bench_stop.wide_show``); once every agent is on the bus and has settled, for
  ``--idle-s``: each agent's RSS (VmRSS) and CPU share (utime+stime over wall time, from /proc),
  planning workers running, and the status and telemetry messages heard per vehicle per second.
  The peer is the same show run from other code: ``--peer-commit REV`` (exported with
  ``git archive`` into a temporary folder; 7b61496 is the code before the light agents) or an
  exported ``--peer-tree DIR``; without either, only ours.
- **loop under planning**: one agent service in this process (real Zenoh router and session, the
  show's simulated vehicle, the loop at 100 Hz: resting off) while twelve characters are planned
  through its job work, ``PLAN_ROUNDS`` times. Period jitter = |tick interval - 10 ms|, p50/p99/max,
  with nothing planned, during the first plan (the worker's start) and during the others; planning
  wall time over CPU time. Peers: the same service with the planning in threads of its own process
  (the code path before this change, warmed up first as that agent was), and a bare asyncio loop
  sleeping to a 100 Hz schedule.
"""

from __future__ import annotations

import argparse
import asyncio
import itertools
import os
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_stop import wait_present, wide_show  # noqa: E402

from bus.keys import ShowKeys  # noqa: E402
from bus.messages import (  # noqa: E402
    AgentReport,
    CommandReply,
    JobAssignment,
    Telemetry,
    VehicleStatus,
)
from bus.pubsub import declare_token, subscribe  # noqa: E402
from bus.rpc import serve  # noqa: E402
from bus.session import BusSettings, open_session  # noqa: E402
from showfile import load_show  # noqa: E402
from trust.settings import ensure_show_keys, session_settings  # noqa: E402

AIRSHOW = ROOT / "shows" / "airshow-2014.yaml"
CHARACTERS = ("永", "書", "鬱", "A", "龍", "風", "雲", "飛", "鳥", "魚", "B", "水")
PLAN_ROUNDS = 4
"""Times the characters are planned: one round gives ~45 ticks of planning, whose p99 is their
maximum; four give ~180."""
"""Planned while the loop's jitter is measured (the first one starts the planning worker)."""
PERIOD_S = 0.01
QUIET_S = 5.0
"""Loop measured with nothing planned for this long in [s]."""


# --- idle fleet ----------------------------------------------------------------------------------
@dataclass(frozen=True)
class FleetIdle:
    """Idle figures of one show run."""

    agents: int
    rss_mib: list[float]
    cpu_percent: list[float]
    workers: int
    status_hz: float
    telemetry_hz: float


def process_ids(marker: str, show_path: Path) -> list[int]:
    """Processes whose command line holds ``marker`` and the show's path."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            argv = (entry / "cmdline").read_bytes().split(b"\0")
        except OSError:
            continue
        words = [a.decode(errors="replace") for a in argv]
        if marker in words and str(show_path) in words:
            found.append(int(entry.name))
    return found


def worker_count(parents: Sequence[int]) -> int:
    """Planning workers among the children of ``parents``."""
    count = 0
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes()
            ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        if ppid in parents and b"vehicle_agent.plan_worker" in cmdline:
            count += 1
    return count


def rss_mib(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return float("nan")


def cpu_ticks(pid: int) -> int:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return int(fields[11]) + int(fields[12])


def measure_idle(tree: Path, count: int, idle_s: float, start_timeout_s: float) -> FleetIdle:
    """Start the widened show from ``tree``, measure it idle, stop it."""
    env = dict(os.environ, PYTHONPATH=str(tree), PYTHONUNBUFFERED="1")
    with tempfile.TemporaryDirectory() as tmp:
        path, show = wide_show(Path(tmp), count)
        ensure_show_keys(show)
        up = subprocess.Popen(
            [sys.executable, "-m", "cli.main", "up", str(path), "--headless", "--no-kiosk"],
            cwd=tree,
            env=env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            wait_present(show, start_timeout_s)
            time.sleep(10.0)  # settled: warm-ups done, nothing but the idle loop left
            pids = process_ids("agent", path)
            keys = ShowKeys(show.show_id)
            heard = {"status": 0, "telemetry": 0}

            def counter(kind: str) -> Callable[[str, object], None]:
                def on_message(_key: str, _message: object) -> None:
                    heard[kind] += 1

                return on_message

            with open_session(session_settings(show, "operator"), role="client") as session:
                subs = [
                    subscribe(session, keys.vehicle_status_all, VehicleStatus, counter("status")),
                    subscribe(session, keys.telemetry_all, Telemetry, counter("telemetry")),
                ]
                ticks0 = {pid: cpu_ticks(pid) for pid in pids}
                started = time.monotonic()
                heard.update(status=0, telemetry=0)
                time.sleep(idle_s)
                wall_s = time.monotonic() - started
                ticks1 = {pid: cpu_ticks(pid) for pid in pids}
                rss = [rss_mib(pid) for pid in pids]
                workers = worker_count(pids)
                del subs
        finally:
            subprocess.run(
                [sys.executable, "-m", "cli.main", "down", str(path), "--timeout", "300"],
                cwd=tree,
                env=env,
                capture_output=True,
                timeout=320,
            )
            up.wait(timeout=320)
    hz = os.sysconf("SC_CLK_TCK")
    cpu = [100.0 * (ticks1[p] - ticks0[p]) / hz / wall_s for p in pids]
    per_vehicle_s = wall_s * max(1, len(pids))
    return FleetIdle(
        agents=len(pids),
        rss_mib=rss,
        cpu_percent=cpu,
        workers=workers,
        status_hz=heard["status"] / per_vehicle_s,
        telemetry_hz=heard["telemetry"] / per_vehicle_s,
    )


def print_idle(label: str, idle: FleetIdle) -> None:
    rss, cpu = idle.rss_mib, idle.cpu_percent
    print(
        f"  {label:<28} {idle.agents:3d} agents: RSS median {statistics.median(rss):6.1f} MiB "
        f"(max {max(rss):6.1f}, total {sum(rss) / 1024:5.2f} GiB); CPU median "
        f"{statistics.median(cpu):4.2f} % (total {sum(cpu) / 100:4.2f} cores); "
        f"status {idle.status_hz:4.2f} Hz, telemetry {idle.telemetry_hz:5.2f} Hz per vehicle; "
        f"planning workers {idle.workers}"
    )


# --- the loop under planning ---------------------------------------------------------------------
@dataclass(frozen=True)
class LoopFigures:
    """Period jitter in [ms] and planning times of one run."""

    quiet_ms: list[float]
    cold_ms: list[float]
    """While the first job is planned (the worker starts and imports the planner)."""
    planning_ms: list[float]
    """While the other jobs are planned."""
    wall_s: list[float]
    cpu_s: list[float]
    worker_rss_mib: float | None


def jitter_ms(starts: Sequence[float], within: Sequence[tuple[float, float]]) -> list[float]:
    """|interval - period| in [ms] of the ticks that began inside one of the windows."""
    out = []
    for a, b in itertools.pairwise(starts):
        if any(lo <= b <= hi for lo, hi in within):
            out.append(abs(b - a - PERIOD_S) * 1e3)
    return out


def percentiles(values: Sequence[float]) -> str:
    if not values:
        return "no ticks"
    ordered = sorted(values)
    p99 = ordered[min(len(ordered) - 1, int(0.99 * len(ordered)))]
    return (
        f"p50 {statistics.median(ordered):5.2f} ms, p99 {p99:6.2f} ms, "
        f"max {ordered[-1]:7.2f} ms ({len(ordered)} ticks)"
    )


async def loop_under_planning(in_process: bool, port: int) -> LoopFigures:
    from vehicle_agent.agent import make_backend, make_runner
    from vehicle_agent.jobs import job_metrics, prepare_job
    from vehicle_agent.service import AgentService
    from vehicle_agent.service_settings import ServiceSettings
    from vehicle_agent.setup import vehicle_setup
    from vehicle_agent.work import JobWork, ThreadJobWork
    from vehicle_agent.worker_client import ProcessJobWork

    show = load_show(AIRSHOW)
    setup = vehicle_setup(show, show.vehicles[0].id, time_scale=1.0)
    cpu_of_plans: list[float] = []
    work: JobWork
    if in_process:

        def timed_prepare(assignment: JobAssignment) -> object:
            started = time.thread_time()
            try:
                return prepare_job(setup, assignment)
            finally:
                cpu_of_plans.append(time.thread_time() - started)

        prepare_job(setup, JobAssignment(job_id="warm-up", text="一"))  # as the old agent did
        work = ThreadJobWork(
            timed_prepare,  # type: ignore[arg-type]
            lambda prepared, trace: job_metrics(setup, prepared, trace),
        )
    else:
        process_work = ProcessJobWork(show, setup.vehicle_id, 1.0)
        work = process_work
    endpoint = f"tcp/127.0.0.1:{port}"
    bus = BusSettings(router_listen=[endpoint], connect=[endpoint])
    keys = ShowKeys(show.show_id)
    with open_session(bus, role="router"), open_session(bus, role="client") as orch:
        declare_token(orch, keys.orchestrator_alive)
        ack = serve(
            orch, keys.report(setup.vehicle_id), AgentReport, lambda _r: CommandReply(ok=True)
        )
        settings = ServiceSettings(show_id=show.show_id, zenoh=bus, rest_period_s=None)
        service = AgentService(settings, make_runner(setup), make_backend(setup), work)
        stop = asyncio.Event()
        task = asyncio.create_task(service.run(stop))
        while not service.runner.orchestrator_alive:
            await asyncio.sleep(0.05)
        quiet = (time.monotonic(), time.monotonic() + QUIET_S)
        await asyncio.sleep(QUIET_S)
        windows, walls, cpus = [], [], []
        for i, text in enumerate(CHARACTERS * PLAN_ROUNDS):
            started = time.monotonic()
            await work.prepare(JobAssignment(job_id=f"bench-{i}", text=text))
            windows.append((started, time.monotonic()))
            walls.append(time.monotonic() - started)
            if not in_process:
                cpus.append(process_work.last_cpu_s)
            await asyncio.sleep(0.2)
        starts = list(service.tick_starts_s)
        worker_pid = None if in_process else process_work.pid
        worker_rss = None if worker_pid is None else rss_mib(worker_pid)
        stop.set()
        await task
        del ack
    return LoopFigures(
        quiet_ms=jitter_ms(starts, [quiet]),
        cold_ms=jitter_ms(starts, windows[:1]),
        planning_ms=jitter_ms(starts, windows[1:]),
        wall_s=walls,
        cpu_s=cpu_of_plans if in_process else cpus,
        worker_rss_mib=worker_rss,
    )


async def bare_loop() -> list[float]:
    """A bare asyncio loop sleeping to a 100 Hz schedule for QUIET_S: its period jitter."""
    starts, start = [], time.monotonic()
    for tick in range(int(QUIET_S / PERIOD_S)):
        await asyncio.sleep(max(0.0, start + tick * PERIOD_S - time.monotonic()))
        starts.append(time.monotonic())
    return jitter_ms(starts, [(starts[0], starts[-1])])


def print_loop(label: str, figures: LoopFigures) -> None:
    ratios = [w / c for w, c in zip(figures.wall_s, figures.cpu_s, strict=False) if c > 0]
    print(f"  {label}")
    print(f"    jitter, nothing planned: {percentiles(figures.quiet_ms)}")
    print(f"    jitter, first plan:      {percentiles(figures.cold_ms)}")
    print(f"    jitter, while planning:  {percentiles(figures.planning_ms)}")
    first = len(CHARACTERS)  # the first round's, each character once
    walls = ", ".join(f"{w:.2f}" for w in figures.wall_s[:first])
    cpus = ", ".join(f"{c:.2f}" for c in figures.cpu_s[:first])
    print(f"    plans {''.join(CHARACTERS)} ({PLAN_ROUNDS} rounds; the first): wall {walls} s")
    print(f"    CPU {cpus} s")
    if ratios:
        print(
            f"    planning wall/CPU: median {statistics.median(ratios):.2f}, max {max(ratios):.2f}"
        )
    if figures.worker_rss_mib is not None:
        print(f"    planning worker RSS after the plans: {figures.worker_rss_mib:.0f} MiB")


def export_commit(rev: str, into: Path) -> Path:
    """The files of commit ``rev`` of this repository, written under ``into``."""
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", rev], capture_output=True, check=True
    ).stdout
    subprocess.run(["tar", "-x", "-C", str(into)], input=archive, check=True)
    return into


def free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", type=int, default=10)
    parser.add_argument("--peer-tree", type=Path, default=None)
    parser.add_argument("--peer-commit", default=None)
    parser.add_argument("--idle-s", type=float, default=20.0)
    parser.add_argument("--start-timeout", type=float, default=900.0)
    parser.add_argument("--skip-fleet", action="store_true")
    parser.add_argument("--skip-loop", action="store_true")
    args = parser.parse_args()
    if not args.skip_loop:
        print("loop under planning (one agent, 100 Hz, time scale 1):")
        print(f"  bare asyncio loop at 100 Hz:  {percentiles(asyncio.run(bare_loop()))}")
        print_loop(
            "planning in threads (before)", asyncio.run(loop_under_planning(True, free_port()))
        )
        print_loop(
            "planning worker process (now)", asyncio.run(loop_under_planning(False, free_port()))
        )
    if not args.skip_fleet:
        print(f"idle fleet ({args.vehicles} sim vehicles, {args.idle_s:.0f} s idle):")
        with tempfile.TemporaryDirectory() as tmp:
            peer_tree = args.peer_tree
            if args.peer_commit is not None:
                peer_tree = export_commit(args.peer_commit, Path(tmp))
            if peer_tree is not None:
                peer = measure_idle(peer_tree, args.vehicles, args.idle_s, args.start_timeout)
                print_idle(f"peer {args.peer_commit or peer_tree}", peer)
        ours = measure_idle(ROOT, args.vehicles, args.idle_s, args.start_timeout)
        print_idle("this tree", ours)


if __name__ == "__main__":
    main()
