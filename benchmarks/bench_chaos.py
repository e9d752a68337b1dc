"""Chaos soak: does the Airshow show recover by itself from every fault, losing nothing?

    python benchmarks/bench_chaos.py                          # 120 min of show time each run
    python benchmarks/bench_chaos.py --show-minutes 40 --seed 3
    python benchmarks/bench_chaos.py --once --gap-s 2 --hold-scale 0.35  # each kind once

Runs ``shows/airshow-2014.yaml`` (every process supervised, as under ``skyquill up``; real Zenoh,
mutual TLS, SQLite) at ``--time-scale`` (4) twice for the same time: once without faults (the
peer), once with a seeded schedule of faults, one every 2-4 minutes of show time, drawn from
(each kind once before any repeats):

- ``kill_router``, ``kill_orchestrator``: SIGKILL, the supervisor restarts it;
- ``kill_agent_writing``, ``kill_agent_idle``, ``kill_agent_taking_off``: SIGKILL of an agent in
  that state (another if none is within 20 s; the fault is then named by that one's state);
- ``stop_agent``: SIGSTOP of a writing agent for 20 s; ``stop_orchestrator``: for 10 s;
- ``estop_one``: E-STOP of a writing vehicle, then the console's documented way back (reset its
  fault once it rests, release it; the crew's fresh sheet);
- ``land_all``: land all, then release all and resume once every vehicle is down;
- ``cut_vehicle``: a writing vehicle's agent cut off the network for 10 s (every client reaches
  the router through a relay that can cut one process off, ``chaos_relay.py``);
- ``disk_full``: the show's disk (a tmpfs of its own, ``chaos_disk.py``) full to the last byte
  for 30 s; a submission made meanwhile must be refused in one clear line, and nothing
  acknowledged lost. Needs root: without, not injected (said in the output).

A feeder keeps ``--waiting`` characters waiting (a submission retried with its idempotency key
until acknowledged); the crew (``cli.showrun.Stagehand``) replaces the sheet of every board left
half-written, and the script releases vehicles the orchestrator holds (lost in the air, in
fault), counting each as an operator action: those of a vehicle lost in the air, which issue 29
wants held until the operator has looked at it, and those of the operator's own stops are the
scripted recoveries; any other is an extra action. Printed: characters done per hour and the
ratio to the peer (target >= 85 %), acknowledged submissions lost (0), characters written twice
in full (job folders per job; 0), half-written boards and the fault before each (only agent
kills and e-stops may leave one), operator actions beyond the scripted recoveries (0), recovery
time per fault kind (p50, max: from the fault until every vehicle is present, out of fault and
not held again, watched once the fault shows), and every process's memory at the start and the
end. Load (``os.getloadavg``) beside the figures.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import random
import sqlite3
import statistics
import sys
import tempfile
import threading
import time
from collections import Counter
from dataclasses import dataclass
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from bench_show import SHOW, wait_ready  # noqa: E402
from bench_soak import Jobs, keep_waiting, memory_bytes  # noqa: E402
from chaos_disk import OwnDisk, unavailable  # noqa: E402
from chaos_inject import (  # noqa: E402
    FAULTS,
    HALF_WRITE_ALLOWED,
    SCRIPTED_HOLDS,
    Chaos,
    Log,
    Operator,
    inject,
    recovered,
    release_holds,
)
from chaos_relay import CutRelay  # noqa: E402

from bus.messages import Event, JobState  # noqa: E402
from bus.pubsub import subscribe  # noqa: E402
from bus.session import free_tcp_endpoint  # noqa: E402
from cli.showrun import ShowRun, Stagehand, derived_show  # noqa: E402
from showfile import Show, dump_show, load_show  # noqa: E402
from vehicle_agent.job_files import written_whole  # noqa: E402


@dataclass
class Result:
    name: str
    minutes: float
    done: int
    acknowledged: list[str]
    states: dict[str, str]
    folders: Counter[str]
    log: Log
    memory: dict[str, tuple[int | None, int | None]]
    load: tuple[float, float, float]

    @property
    def per_hour(self) -> float:
        return self.done / (self.minutes / 60.0)


def _through_relay(path: Path, show: Show) -> tuple[Path, Show, int, int]:
    """``show`` with its clients connecting to a relay port in front of its router; returns the
    show, the relay's port and the router's."""
    listen = show.zenoh.router_listen[0]
    relay = free_tcp_endpoint()
    zenoh = show.zenoh.model_copy(update={"connect": (relay,)})
    dump_show(show.model_copy(update={"zenoh": zenoh}), path)
    return path, load_show(path), _port(relay), _port(listen)


def _port(endpoint: str) -> int:
    """``tls/127.0.0.1:7447`` -> 7447."""
    return int(endpoint.rsplit(":", 1)[1])


def run_show(args: argparse.Namespace, out: Path, chaos: bool) -> Result:
    """One run of the show, its storage on a disk of its own where it can be filled (root); its
    processes' logs beside, in ``<out>-logs``."""
    if unavailable() is not None:
        return _run_show(args, out, chaos, None)
    with OwnDisk(out) as disk:
        return _run_show(args, out, chaos, disk)


def _run_show(args: argparse.Namespace, out: Path, chaos: bool, disk: OwnDisk | None) -> Result:
    path, show = derived_show(SHOW, out, time_scale=args.time_scale)
    path, show, relay_port, router_port = _through_relay(path, show)
    log, jobs = Log(), Jobs()
    if disk is None:
        log.skipped["disk_full"] = str(unavailable())
    relay = CutRelay(relay_port, router_port)
    with (
        contextlib.closing(relay),
        ShowRun(path, show, log_dir=out.with_name(out.name + "-logs")) as run,
        run.client() as session,
        Stagehand(session, run.keys, period_s=1.0),
    ):
        relay.owners = lambda: _pids(run)
        subs = [
            subscribe(session, run.keys.events, Event, log.on_event),
            subscribe(session, run.keys.jobs_all, JobState, jobs.on_job),
        ]
        wait_ready(run, session, len(show.vehicles), timeout_s=180.0)
        memory_start = _memory(run)
        strike = Chaos(Operator(session, run), run, relay, disk, log, args.hold_scale)
        minutes, done = _feed_and_strike(args, chaos, strike, session, jobs)
        memory_end = _memory(run)
        acknowledged = list(jobs.last)
        for sub in subs:
            sub.undeclare()  # type: ignore[no-untyped-call]
    memory = {k: (memory_start.get(k), memory_end.get(k)) for k in {*memory_start, *memory_end}}
    name = "chaos" if chaos else "fault-free"
    return Result(name, minutes, done, acknowledged, _stored_states(show), _whole_folders(show),
                  log, memory, os.getloadavg())  # fmt: skip


def _feed_and_strike(
    args: argparse.Namespace, chaos: bool, strike: Chaos, session: object, jobs: Jobs
) -> tuple[float, int]:
    """Keep ``args.waiting`` characters waiting while the faults are struck (none in the
    fault-free run); the wall minutes it ran and the characters done meanwhile."""
    stop = threading.Event()
    feeder = threading.Thread(
        target=keep_waiting, args=(stop, strike.run, session, jobs, args.waiting), daemon=True
    )
    start = time.monotonic()
    done_at_start = jobs.counts()["done"]
    feeder.start()
    _strike_faults(args, chaos, strike, start)
    minutes = (time.monotonic() - start) / 60.0
    done = jobs.counts()["done"] - done_at_start
    stop.set()
    feeder.join()
    return minutes, done


def _strike_faults(args: argparse.Namespace, chaos: bool, strike: Chaos, start: float) -> None:
    """For ``args.show_minutes`` of show time from ``start`` (monotonic [s]) release the vehicles
    held, and in the chaos run strike a fault after every gap, each kind once before any repeats
    (``--once``: each kind once, then end)."""
    wall_s = args.show_minutes * 60.0 / args.time_scale
    rng = random.Random(args.seed)
    op, log = strike.op, strike.log
    order = [kind for kind in FAULTS if kind not in log.skipped]
    rng.shuffle(order)
    next_fault = start + _gap_s(args, rng)
    while time.monotonic() < start + wall_s:
        time.sleep(0.5)
        release_holds(op, log)
        if not chaos or time.monotonic() < next_fault:
            continue
        if not order and args.once:
            break  # every kind struck once, and the show given a gap after the last
        kind = order.pop(0) if order else rng.choice(FAULTS)
        if kind in log.skipped:
            continue
        _strike(kind, strike, start)
        next_fault = time.monotonic() + _gap_s(args, rng)


def _strike(kind: str, strike: Chaos, start: float) -> None:
    """Strike a fault of ``kind`` (logged by the kind it was struck as; printed with the seconds
    since ``start``, monotonic [s]), watch for it to show, then time the recovery, the operator
    releasing holds meanwhile."""
    op, log = strike.op, strike.log
    vehicles = len(strike.run.show.vehicles)
    struck = time.time()
    log.faults.append((struck, kind))
    print(f"  {time.monotonic() - start:6.0f} s  {kind}", flush=True)
    if (actual := inject(kind, strike)) != kind:
        print(f"           (struck as {actual})", flush=True)
        log.faults[-1] = (struck, actual)
    released = lambda: release_holds(op, log)  # noqa: E731 - the operator watches on
    op.until(lambda f: not recovered(f, vehicles), NOTICE_S)  # a kill shows late
    if op.until(lambda f: recovered(f, vehicles), 120.0, released):
        log.recovered_s[log.faults[-1][1]].append(time.time() - struck)


def _stored_states(show: Show) -> dict[str, str]:
    """Every job's state in the show's database (read-only, once the show has stopped)."""
    stored = sqlite3.connect(f"file:{show.database_path}?mode=ro", uri=True)
    try:
        return dict(stored.execute("SELECT job_id, state FROM jobs").fetchall())
    finally:
        stored.close()


def _whole_folders(show: Show) -> Counter[str]:
    """Job folders per job: attempts written to their end (a broken-off one keeps its folder
    too)."""
    job_dirs = show.database_path.parent / "jobs"
    return (
        Counter(p.name.split("-")[0] for p in job_dirs.iterdir() if written_whole(p))
        if job_dirs.is_dir()
        else Counter()
    )


NOTICE_S = 3.0
"""How long after a fault [s] the fleet is watched for it to show (a vehicle is taken as lost
``policy.lost_after_s``, 1.5 s, after its agent died) before its recovery is timed."""


def _gap_s(args: argparse.Namespace, rng: random.Random) -> float:
    """Wall [s] until the next fault: ``--gap-s``, or 2-4 minutes of show time."""
    return float(args.gap_s or rng.uniform(120.0, 240.0) / args.time_scale)


def _pids(run: ShowRun) -> dict[str, int]:
    """The show's processes that may be cut off: name -> pid."""
    found = {}
    for name in run.supervisor.names:
        pid = run.supervisor.pid(name)
        if pid is not None:
            found[name] = pid
    return found


def _memory(run: ShowRun) -> dict[str, int]:
    sizes = {}
    for name in run.supervisor.names:
        pid = run.supervisor.pid(name)
        measured = memory_bytes(pid) if pid is not None else None
        if measured is not None:
            sizes[name] = measured[0]
    return sizes


def half_written(chaos: Result) -> list[tuple[Event, str]]:
    """Every board left half-written, with the fault struck last before it."""
    log = chaos.log
    return [(e, log.fault_before(e.time_s)) for e in log.events if e.kind == "board_dirty"]


def _lost_in_air(log: Log, vehicle_id: str, released_s: float) -> bool:
    """Whether the hold released then was of a vehicle lost in the air (the operator must look
    at it: a scripted recovery, whatever fault was meant; an agent killed as it took off)."""
    held = [e for e in log.events if e.kind == "vehicle_held" and e.vehicle_id == vehicle_id]
    before = [e for e in held if e.time_s <= released_s]
    return bool(before) and "lost while" in before[-1].message


def verdict(chaos: Result) -> list[str]:
    """The targets the chaos run missed (characters per hour apart: that needs the peer)."""
    missed = []
    lost = [j for j in chaos.acknowledged if j not in chaos.states]
    if lost:
        missed.append(f"acknowledged submissions lost: {lost}")
    twice = sorted(j for j, n in chaos.folders.items() if n > 1)
    if twice:
        missed.append(f"characters written twice in full: {twice}")
    log = chaos.log
    unexpected = [cause for _, cause in half_written(chaos) if cause not in HALF_WRITE_ALLOWED]
    if unexpected:
        missed.append(f"half-written boards after faults that should leave none: {unexpected}")
    extra = [(v, log.fault_before(t)) for t, v in log.releases if not _lost_in_air(log, v, t)]
    extra = [(v, cause) for v, cause in extra if cause not in SCRIPTED_HOLDS]
    if extra:
        missed.append(f"releases of held vehicles beyond the scripted recoveries: {extra}")
    struck = Counter(kind for _, kind in log.faults)
    unrecovered = [k for k, n in struck.items() if len(log.recovered_s.get(k, [])) < n]
    if unrecovered:
        missed.append(f"not recovered within 120 s: {unrecovered}")
    unclear = [a for a in log.refusals if not a.startswith("storage_full:")]
    if unclear:
        missed.append(f"a submission while the disk was full was answered: {unclear}")
    return missed


def report(peer: Result, chaos: Result) -> None:
    mib = 1024.0 * 1024.0
    for r in (peer, chaos):
        load = ", ".join(f"{x:.1f}" for x in r.load)
        print(f"{r.name:10}: {r.done} characters in {r.minutes:.1f} min wall, "
              f"{r.per_hour:.0f}/h (load {load})")  # fmt: skip
    ratio = chaos.per_hour / peer.per_hour if peer.per_hour else float("nan")
    print(f"chaos / fault-free characters per hour: {ratio:.1%} (target >= 85 %)")
    log = chaos.log
    dirty = half_written(chaos)
    causes = dict(Counter(cause for _, cause in dirty))
    print(f"half-written boards: {len(dirty)} {causes} (only {', '.join(HALF_WRITE_ALLOWED)}"
          " may leave one); fresh sheets by the crew")  # fmt: skip
    releases = len(log.releases)
    print(f"releases of held vehicles: {releases} (the scripted recoveries' included)")
    missed = verdict(chaos)
    print("targets missed: " + ("none (0 lost, 0 written twice, 0 extra actions)" if not missed
                                else "; ".join(missed)))  # fmt: skip
    print("recovery per fault kind (until every vehicle is present, out of fault, not held):")
    for kind in FAULTS:
        times = log.recovered_s.get(kind, [])
        struck = sum(1 for _, k in log.faults if k == kind)
        if times:
            print(f"  {kind:22} x{struck}: p50 {statistics.median(times):5.1f} s, "
                  f"max {max(times):5.1f} s")  # fmt: skip
        else:
            print(f"  {kind:22} x{struck}: {'not recovered' if struck else 'not drawn'}")
    for kind, why in log.skipped.items():
        print(f"  {kind:22} not injected: {why}")
    for answer in log.refusals:
        print(f"  a submission while the disk was full: {answer}")
    print("memory (RSS MiB, chaos run: start -> end):")
    for name, (a, b) in sorted(chaos.memory.items()):
        start = "-" if a is None else f"{a / mib:.0f}"
        end = "-" if b is None else f"{b / mib:.0f}"
        print(f"  {name:18} {start:>5} -> {end:>5}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--show-minutes", type=float, default=120.0, help="each run, show time")
    parser.add_argument("--time-scale", type=float, default=4.0)
    parser.add_argument("--waiting", type=int, default=6, help="characters kept waiting")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--quick", action="store_true", help="12 show minutes each (a smoke run)")
    parser.add_argument("--out-dir", type=Path, help="keep the runs' files here")
    parser.add_argument("--once", action="store_true", help="strike each fault kind once, then end")
    parser.add_argument(
        "--gap-s", type=float, help="wall [s] between faults (default: 2-4 show min)"
    )
    parser.add_argument("--hold-scale", type=float, default=1.0, help="scale the lasting faults")
    args = parser.parse_args()
    if args.quick:
        args.show_minutes = 12.0
    with tempfile.TemporaryDirectory(prefix="chaos-") as tmp:
        out = args.out_dir or Path(tmp)
        print(f"fault-free run: {args.show_minutes:.0f} show minutes at x{args.time_scale:g}")
        peer = run_show(args, out / "peer", chaos=False)
        print(f"chaos run: seed {args.seed}")
        chaos = run_show(args, out / "chaos", chaos=True)
        report(peer, chaos)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
