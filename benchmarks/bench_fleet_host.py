"""Fleet host: N simulated vehicles' agents in one process, M of them writing at once, in real time.

    nice -n 15 .venv/bin/python benchmarks/bench_fleet_host.py [--vehicles 50,100] [--hosts 1]
        [--writing 50] [--window-s 20] [--peer 10] [--skip-peer] [--profile PATH]

Each case is a real show (``bench_stop.wide_show``: the Airshow show widened to N vehicles, each
over its own board, time scale 1, mutual TLS) run as separate processes: the router, the real
orchestrator, and the vehicles' agents. M characters are submitted at once; once M vehicles are
awake (flying), for ``--window-s`` seconds:

- **real-time factor** of the awake vehicles: control ticks run over ticks due by the wall clock
  (a simulated vehicle never skips a tick: 1.00 is real time, 0.5 half speed), counted in the
  fleet processes; and for agents and fleet alike from telemetry (agent time over wall time);
- **tick jitter** |tick interval - 10 ms| p50/p99 of the awake vehicles' loops, and the event
  loop's lag (a 10 ms timer's lateness), in the fleet process;
- **RSS** of the fleet process (and per vehicle), of its planning workers; **CPU** in cores,
  and that of the orchestrator and of the router, idle and in the window;
- **status latency**: the orchestrator's snapshot query (what ``skyquill status`` asks), every
  0.5 s from this process, and one ``skyquill status`` command's wall time;
- **nothing lost**: every submitted job finished ``done`` (waited for after the window);
- **stop**: how long the fleet process took to stop after SIGTERM, SIGKILLed or not.

``--hosts K`` splits the N vehicles over K fleet processes (a show's ``fleet_hosts: K``): one
Python process runs on one core at most. The peer, in the same run: the same show with
``--peer`` vehicles as separate agent processes (one each, what ``skyquill up`` ran before
``fleet_hosts``) beside a fleet host of as many.
The fleet host of the benchmark is ``fleet_host_child.py``: ``vehicle_agent.fleet``'s
``FleetHost`` as ``skyquill fleet`` runs it, plus a task writing its figures once a second.

The latest figures (quiet 2-core machine, the show's own processes loading it to 3-6): 250
vehicles in 2 hosts, 50 writing, real-time factor 0.97-1.00 (1.00 in three runs of four), 50/50
done, status p95 <= 0.1 s, fleet steps per tick 1.05-1.07. Every run so far, what it found and
what changed because of it: ``docs/fleet_host_measurements.md``.

``--profile PATH`` writes a cProfile of each fleet host to ``PATH.<host number>``.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from bench_agent import cpu_ticks, rss_mib, worker_count  # noqa: E402
from bench_stop import wait_present, wide_show  # noqa: E402
from fleet_host_child import STATS_PERIOD_S  # noqa: E402

from bus.keys import ShowKeys  # noqa: E402
from bus.messages import Telemetry  # noqa: E402
from bus.pubsub import subscribe  # noqa: E402
from bus.rpc import NoReplyError, RemoteError  # noqa: E402
from bus.session import open_session  # noqa: E402
from cli.showrun import snapshot, submit_texts  # noqa: E402
from cli.supervisor import (  # noqa: E402
    ChildSpec,
    Supervisor,
    child_env,
    fleet_stop_grace_s,
    show_children,
    skyquill_argv,
)
from showfile import dump_show, load_show  # noqa: E402
from trust.settings import ensure_show_keys, session_settings  # noqa: E402

CORPUS = ("永", "書", "龍", "風", "雲", "飛", "鳥", "魚", "水", "鬱")
"""Characters written (cycled), long enough to keep M vehicles writing through the window."""
CHILD = Path(__file__).resolve().parent / "fleet_host_child.py"
"""The fleet host process of a case."""


# --- one case ------------------------------------------------------------------------------------
@dataclass
class Case:
    """The figures of one show run."""

    label: str
    vehicles: int
    writing: int
    processes: int = 0
    idle_rss_mib: float = 0.0
    idle_cpu_cores: float = 0.0
    idle_service_cores: dict[str, float] = field(default_factory=dict)
    """Cores of the orchestrator and of the router while every vehicle is idle."""
    service_cores: dict[str, float] = field(default_factory=dict)
    """Cores of the orchestrator and of the router in the writing window."""
    rss_mib: float = 0.0
    worker_rss_mib: float = 0.0
    workers: int = 0
    cpu_cores: float = 0.0
    awake: float = 0.0
    rtf: float = float("nan")
    steps_per_tick: float = float("nan")
    """Fleet steps per control tick in a host (1.0: its vehicles in flight always stepped
    together; each extra step split the fleet)."""
    telemetry_rtf: float = float("nan")
    jitter_ms: list[float] = field(default_factory=list)
    lag_ms: list[float] = field(default_factory=list)
    status_s: list[float] = field(default_factory=list)
    status_cli_s: float = float("nan")
    done: int = 0
    final: int = 0
    stop_s: float = float("nan")
    killed: list[str] = field(default_factory=list)


class TelemetryClock:
    """Per vehicle, the first and last (wall, agent time) of telemetry heard with a job."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.since_s = float("inf")
        self.first: dict[str, tuple[float, float]] = {}
        self.last: dict[str, tuple[float, float]] = {}

    def heard(self, _key: str, message: Telemetry) -> None:
        now_s = time.monotonic()
        if message.job_id is None or now_s < self.since_s:
            return
        with self.lock:
            self.first.setdefault(message.vehicle_id, (now_s, message.t_s))
            self.last[message.vehicle_id] = (now_s, message.t_s)

    def factor(self) -> float:
        """Agent time over wall time of the vehicles heard flying a job."""
        with self.lock:
            pairs = [(self.first[v], self.last[v]) for v in self.first]
        wall = sum(b[0] - a[0] for a, b in pairs)
        agent = sum(b[1] - a[1] for a, b in pairs)
        return agent / wall if wall > 0 else float("nan")


def case_show(out: Path, count: int) -> tuple[Path, object]:
    path, show = wide_show(out, count)
    show = show.model_copy(update={"time_scale": 1.0})
    dump_show(show, path)
    return path, load_show(path)


def run_case(
    label: str, count: int, writing: int, window_s: float, *, hosts: int, profile: str | None = None
) -> Case:
    """One show run: ``hosts`` fleet host processes (0: one agent process per vehicle)."""
    case = Case(label, count, writing)
    with tempfile.TemporaryDirectory() as tmp:
        path, show = case_show(Path(tmp), count)
        ensure_show_keys(show)  # type: ignore[arg-type]
        ids = [v.id for v in show.vehicles]  # type: ignore[attr-defined]
        logs = Path(tmp) / "logs"
        specs = show_children(path, [] if hosts else ids, log_dir=logs)
        stats = [Path(tmp) / f"fleet{i + 1}.jsonl" for i in range(hosts)]
        for i, figures in enumerate(stats):
            group = ids[i::hosts]  # dealt round-robin, as cli/fleets.py does
            argv: tuple[str, ...] = (sys.executable, str(CHILD), str(path))
            argv += (",".join(group), str(figures))
            if profile is not None:
                argv += ("--profile", f"{profile}.{i + 1}")
            grace_s = fleet_stop_grace_s(len(group))
            name = f"fleet {i + 1}"
            specs.append(ChildSpec(name, argv, logs / f"fleet{i + 1}.log", None, grace_s))
        supervisor = Supervisor(specs, env=child_env(), say=lambda line: None)
        supervisor.start()
        try:
            measure(case, supervisor, show, path, stats, window_s)
        finally:
            report = supervisor.stop()
            case.killed = report.killed
            agents = [n for n in report.stop_s if n.startswith(("agent", "fleet"))]
            case.stop_s = max((report.stop_s[n] for n in agents), default=float("nan"))
    return case


def measure(
    case: Case,
    supervisor: Supervisor,
    show: object,
    path: Path,
    stats: list[Path],
    window_s: float,
) -> None:
    wait_present(show, 600.0)  # type: ignore[arg-type]
    names = [n for n in supervisor.names if n.startswith(("agent", "fleet"))]
    pids = [p for p in (supervisor.pid(n) for n in names) if p is not None]
    case.processes = len(pids)
    services = {n: supervisor.pid(n) for n in SERVICES}
    time.sleep(5.0)  # settled
    ticks0, idle_s = sum(cpu_ticks(p) for p in pids), time.monotonic()
    service_ticks0 = {n: cpu_ticks(p) for n, p in services.items() if p is not None}
    time.sleep(5.0)
    hz = os.sysconf("SC_CLK_TCK")
    case.idle_cpu_cores = (
        (sum(cpu_ticks(p) for p in pids) - ticks0) / hz / (time.monotonic() - idle_s)
    )
    case.idle_service_cores = cores_since(services, service_ticks0, idle_s)
    case.idle_rss_mib = sum(rss_mib(p) for p in pids)
    keys = ShowKeys(show.show_id)  # type: ignore[attr-defined]
    clock = TelemetryClock()
    with open_session(session_settings(show, "operator"), role="client") as session:  # type: ignore[arg-type]
        heard = subscribe(session, keys.telemetry_all, Telemetry, clock.heard)
        texts = [CORPUS[i % len(CORPUS)] for i in range(case.writing)]
        job_ids = submit_all(session, keys, texts, timeout_s=120.0)
        wait_writing(session, keys, job_ids, timeout_s=180.0)
        started = time.monotonic()
        clock.since_s = started
        ticks0 = sum(cpu_ticks(p) for p in pids)
        service_ticks0 = {n: cpu_ticks(p) for n, p in services.items() if p is not None}
        while time.monotonic() - started < window_s:
            asked = time.monotonic()
            try:
                snapshot(session, keys, timeout_s=5.0)
                case.status_s.append(time.monotonic() - asked)
            except NoReplyError:
                case.status_s.append(float("inf"))
            time.sleep(max(0.0, 0.5 - (time.monotonic() - asked)))
        ended = time.monotonic()
        case.cpu_cores = (sum(cpu_ticks(p) for p in pids) - ticks0) / hz / (ended - started)
        case.service_cores = cores_since(services, service_ticks0, started)
        case.rss_mib = sum(rss_mib(p) for p in pids)
        case.workers = worker_count(pids)
        case.worker_rss_mib = sum(rss_mib(p) for p in worker_pids(pids))
        cli = time.monotonic()
        subprocess.run(skyquill_argv("status", str(path)), env=child_env(), capture_output=True)
        case.status_cli_s = time.monotonic() - cli
        window_figures(case, stats, started, ended)
        case.telemetry_rtf = clock.factor()
        final = wait_final(session, keys, job_ids, timeout_s=600.0)
        heard.undeclare()  # type: ignore[no-untyped-call]
    case.final = len(final)
    case.done = sum(1 for state in final.values() if state == "done")


SERVICES = ("orchestrator", "router")
"""The show's processes besides the vehicles whose CPU is printed."""


def cores_since(
    pids: dict[str, int | None], ticks0: dict[str, int], since_s: float
) -> dict[str, float]:
    """Cores each named process used since ``since_s`` (monotonic) from its ticks then."""
    elapsed_s = time.monotonic() - since_s
    hz = os.sysconf("SC_CLK_TCK")
    return {
        name: (cpu_ticks(pid) - ticks0[name]) / hz / elapsed_s
        for name, pid in pids.items()
        if pid is not None and name in ticks0
    }


def submit_all(session: object, keys: ShowKeys, texts: list[str], timeout_s: float) -> list[str]:
    """Submit each text, retrying while the orchestrator does not answer in time (a query that
    timed out at the router comes back as an error reply, not as none)."""
    deadline = time.monotonic() + timeout_s
    job_ids = []
    for text in texts:
        while True:
            try:
                (reply,) = submit_texts(session, keys, [text], timeout_s=10.0)  # type: ignore[arg-type]
                break
            except (NoReplyError, RemoteError):
                if time.monotonic() > deadline:
                    raise
        job_ids.append(str(reply.job_id))
    return job_ids


def worker_pids(parents: Sequence[int]) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            cmdline = (entry / "cmdline").read_bytes()
            ppid = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
        except (OSError, ValueError, IndexError):
            continue
        if ppid in parents and b"vehicle_agent.plan_worker" in cmdline:
            found.append(int(entry.name))
    return found


def window_figures(case: Case, stats: list[Path], started: float, ended: float) -> None:
    """The fleet processes' figures of the seconds inside the window."""
    ran = due = 0.0
    stepped = 0
    awake = []
    for path in stats:
        steps_before = 0
        for line in path.read_text().splitlines():
            figures = json.loads(line)
            steps, steps_before = figures["steps"] - steps_before, figures["steps"]
            if not started + STATS_PERIOD_S <= figures["t"] <= ended + STATS_PERIOD_S:
                continue  # a second not wholly inside the window
            ran += figures["ran"]
            due += figures["due"]
            stepped += steps
            awake.append(figures["awake"])
            case.jitter_ms += figures["jitter_ms"]
            case.lag_ms += figures["lag_ms"]
    case.rtf = ran / due if due > 0 else float("nan")
    # one line a second from each host: the mean of a host's count, times the hosts
    case.awake = statistics.mean(awake) * len(stats) if awake else 0.0
    control_ticks = ran / case.awake * len(stats) if case.awake else 0.0  # summed over hosts
    case.steps_per_tick = stepped / control_ticks if control_ticks else float("nan")


def wait_writing(session: object, keys: ShowKeys, job_ids: list[str], timeout_s: float) -> None:
    """Until every job is being written (or ``timeout_s``)."""
    deadline = time.monotonic() + timeout_s
    wanted = set(job_ids)
    states: dict[str, int] = {}
    while time.monotonic() < deadline:
        try:
            jobs = snapshot(session, keys, timeout_s=5.0).jobs  # type: ignore[arg-type]
        except NoReplyError:
            continue
        states = collections.Counter(j.state for j in jobs if j.job_id in wanted)
        if states["writing"] + states["done"] == len(wanted):
            return
        time.sleep(0.5)
    print(
        f"    (not every job under way after {timeout_s:.0f} s: {dict(states)}; measuring anyway)"
    )


def wait_final(
    session: object, keys: ShowKeys, job_ids: list[str], timeout_s: float
) -> dict[str, str]:
    """The final state of each job that reached one within ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    final: dict[str, str] = {}
    while time.monotonic() < deadline and len(final) < len(job_ids):
        try:
            jobs = snapshot(session, keys, timeout_s=5.0).jobs  # type: ignore[arg-type]
        except (NoReplyError, RemoteError):  # a busy orchestrator (load 8-10): ask again
            continue
        for job in jobs:
            if job.job_id in job_ids and job.state in ("done", "failed", "cancelled", "rejected"):
                if job.job_id not in final and job.state != "done":
                    why = job.error.message if job.error is not None else "no reason given"
                    print(f"    job {job.job_id} {job.state} after {job.attempts} attempts: {why}")
                final[job.job_id] = job.state
        time.sleep(1.0)
    return final


# --- printing ------------------------------------------------------------------------------------
def pct(values: Sequence[float], q: float) -> float:
    if not values:
        return float("nan")
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def print_case(case: Case) -> None:
    n = case.vehicles
    print(f"  {case.label}: {n} vehicles in {case.processes} processes, {case.writing} writing")
    print(
        f"    idle: RSS {case.idle_rss_mib:7.1f} MiB ({case.idle_rss_mib / n:5.2f} per vehicle), "
        f"CPU {case.idle_cpu_cores:4.2f} cores ({100 * case.idle_cpu_cores / n:4.2f} % per vehicle)"
    )
    print(
        f"    writing: RSS {case.rss_mib:7.1f} MiB ({case.rss_mib / n:5.2f} per vehicle) + "
        f"{case.workers} planning workers {case.worker_rss_mib:6.1f} MiB; "
        f"CPU {case.cpu_cores:4.2f} cores ({100 * case.cpu_cores / n:4.2f} % per vehicle)"
    )
    for when, cores in (("idle", case.idle_service_cores), ("writing", case.service_cores)):
        figures = ", ".join(f"{name} {value:4.2f}" for name, value in cores.items())
        print(f"    {when}: cores of the {figures}")
    awake = f" ({case.awake:.0f} vehicles awake)" if case.awake else ""
    print(
        f"    real-time factor of the writing vehicles: ticks {case.rtf:5.3f}{awake}, "
        f"telemetry {case.telemetry_rtf:5.3f}; fleet steps per tick {case.steps_per_tick:4.2f}"
    )
    if case.jitter_ms:
        print(
            f"    tick jitter p50 {pct(case.jitter_ms, 0.5):5.2f} ms, p99 "
            f"{pct(case.jitter_ms, 0.99):6.2f} ms ({len(case.jitter_ms)} ticks); loop lag p50 "
            f"{pct(case.lag_ms, 0.5):5.2f} ms, p99 {pct(case.lag_ms, 0.99):6.2f} ms"
        )
    print(
        f"    status: p50 {pct(case.status_s, 0.5):5.3f} s, p95 {pct(case.status_s, 0.95):5.3f} s, "
        f"max {max(case.status_s, default=float('nan')):5.3f} s; `skyquill status` "
        f"{case.status_cli_s:4.2f} s"
    )
    killed = ", ".join(case.killed) or "none"
    print(
        f"    jobs done {case.done}/{case.writing} ({case.final} final); stop "
        f"{case.stop_s:4.1f} s, SIGKILLed: {killed}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--vehicles", default="50", help="comma-separated fleet sizes")
    parser.add_argument("--writing", type=int, default=50)
    parser.add_argument("--window-s", type=float, default=20.0)
    parser.add_argument("--peer", type=int, default=10)
    parser.add_argument("--skip-peer", action="store_true")
    parser.add_argument("--hosts", type=int, default=1, help="fleet host processes per show")
    parser.add_argument("--profile", help="cProfile each fleet host to PROFILE.<host number>")
    args = parser.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    if not args.skip_peer:
        print(f"peer ({args.peer} vehicles, every one writing):")
        print_case(run_case("agent processes", args.peer, args.peer, args.window_s, hosts=0))
        print_case(run_case("fleet host", args.peer, args.peer, args.window_s, hosts=1))
    for count in (int(c) for c in args.vehicles.split(",")):
        writing = min(args.writing, count)
        print(f"{count} vehicles in {args.hosts} fleet hosts ({writing} writing):")
        label = f"{args.hosts} fleet host{'s' if args.hosts > 1 else ''}"
        case = run_case(
            label, count, writing, args.window_s, hosts=args.hosts, profile=args.profile
        )
        print_case(case)
    print(f"load average after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
