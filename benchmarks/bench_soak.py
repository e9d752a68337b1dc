"""Soak: is every process's memory flat, and disk growth bounded, over a long Airshow show?

    python benchmarks/bench_soak.py                      # 60 minutes at time scale 4
    python benchmarks/bench_soak.py --minutes 15 --png soak.png

Runs ``shows/airshow-2014.yaml`` (router, orchestrator, four simulated agents and their planning
workers, real Zenoh on loopback; a copy of the show on a free port, storing in a temporary or
``--out-dir`` directory) and keeps ``--waiting`` characters of a fixed corpus waiting, so the
queue never empties. Every ``--sample-s`` it reads each process's resident set (``/proc``) and
the bytes on disk of job files, MCAP recordings, the SQLite database and its WAL (apart: the
WAL fills to about 4 MB in the first minutes, then is reused).

Printed per process: RSS at start, after warm-up and at the end, its peak, and the least-squares
slope after warm-up in MiB/hour; the same for its anonymous memory (its own heap: RSS also counts
the pages it touched of the Zenoh shared-memory segments, 16 MiB each, that the show's processes
map). Per storage the same slope; characters written per hour, failed jobs and restarts. A
process whose memory levels off has a slope near zero however long the run; one that grows per
job keeps a slope proportional to characters per hour.

The warm-up (``--warmup-minutes``) is by default half the run, up to 25 min: the orchestrator
keeps the latest 500 finished jobs and snapshot replies list as many, so its memory rises until
about 500 characters are written (25 min at time scale 4), then stays flat.

Every finished job should have its ``report.png``, drawn later when the machine is busy: after
the soak the show runs on until every picture is drawn (``--picture-wait-s`` at most), and the
pictures drawn, still waiting and how late they came after their job's ``metrics.json`` are
printed, the last job's among them.

``--trace-memory DIR`` says what grows in the orchestrator (or the ``--trace`` processes), by
allocation site (``memtrace.py``).
"""

from __future__ import annotations

import argparse
import itertools
import sys
import tempfile
import threading
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

from bench_show import SHOW, submit_char, wait_ready  # noqa: E402
from soak_report import plot, progress, report, report_pictures  # noqa: E402

from bus.messages import JobState  # noqa: E402
from bus.pubsub import subscribe  # noqa: E402
from cli.showrun import FINAL_STATES, ShowRun, Stagehand, derived_show  # noqa: E402
from cli.supervisor import ChildSpec  # noqa: E402
from showfile.models import Show  # noqa: E402

CORPUS = "ABQRSgkw" + "永光马和我的是人大中国天"
WAITING_STATES = frozenset({"submitted", "awaiting_approval", "queued"})


def memory_bytes(pid: int) -> tuple[int, int] | None:
    """Resident set of ``pid`` and its anonymous part (its own heap, not files or the Zenoh
    shared-memory segments every process of the show maps), in bytes; None: it is gone."""
    fields: dict[str, int] = {}
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            name, _, value = line.partition(":")
            if name in ("VmRSS", "RssAnon"):
                fields[name] = int(value.split()[0]) * 1024
    except (FileNotFoundError, ProcessLookupError):
        return None
    if len(fields) < 2:
        return None
    return fields["VmRSS"], fields["RssAnon"]


def children_of(pid: int) -> list[int]:
    """Direct children of ``pid`` (e.g. an agent's planning worker)."""
    try:
        tasks = Path(f"/proc/{pid}/task").iterdir()
        found = []
        for task in tasks:
            text = (task / "children").read_text().split()
            found += [int(c) for c in text]
        return found
    except (FileNotFoundError, ProcessLookupError):
        return []


def tree_bytes(path: Path, pattern: str = "**/*") -> int:
    """Bytes of the files under ``path`` matching ``pattern`` (0 when absent)."""
    total = 0
    for f in path.glob(pattern):
        try:
            if f.is_file():
                total += f.stat().st_size
        except FileNotFoundError:
            continue  # pruned meanwhile
    return total


@dataclass
class Jobs:
    """The last state of every job, from ``jobs/*`` publications."""

    last: dict[str, str] = field(default_factory=dict)
    lock: threading.Lock = field(default_factory=threading.Lock)

    def on_job(self, _key: str, job: JobState) -> None:
        with self.lock:
            if self.last.get(job.job_id) not in FINAL_STATES:
                self.last[job.job_id] = job.state

    def submitted(self, job_id: str, state: str) -> None:
        """A job just accepted (its publication may not have arrived yet)."""
        with self.lock:
            self.last.setdefault(job_id, state)

    def counts(self) -> Counter[str]:
        with self.lock:
            return Counter(self.last.values())


@dataclass
class Samples:
    """RSS per process and bytes per storage over time (seconds since the show was ready)."""

    t_s: list[float] = field(default_factory=list)
    rss: dict[str, list[tuple[float, int]]] = field(default_factory=dict)
    anon: dict[str, list[tuple[float, int]]] = field(default_factory=dict)
    disk: dict[str, list[tuple[float, int]]] = field(default_factory=dict)
    done: list[tuple[float, int]] = field(default_factory=list)

    def take(self, t_s: float, run: ShowRun, show: Show, jobs: Jobs) -> None:
        self.t_s.append(t_s)
        for name in run.supervisor.names:
            pid = run.supervisor.pid(name)
            if pid is None:
                continue
            label = name.removeprefix("agent ")
            for k, child in enumerate(children_of(pid)):
                self._memory(f"{label} worker" + (f" {k}" if k else ""), t_s, child)
            self._memory(label, t_s, pid)
        database = show.database_path
        self._add(self.disk, "job files", t_s, tree_bytes(database.parent / "jobs"))
        self._add(self.disk, "recordings", t_s, tree_bytes(show.recordings_dir))
        self._add(self.disk, "sqlite", t_s, tree_bytes(database.parent, database.name))
        wal = tree_bytes(database.parent, database.name + "-wal")  # fills to ~4 MB, then stays
        self._add(self.disk, "sqlite wal", t_s, wal)
        self.done.append((t_s, jobs.counts()["done"]))

    def _memory(self, name: str, t_s: float, pid: int) -> None:
        sizes = memory_bytes(pid)
        if sizes is not None:
            self._add(self.rss, name, t_s, sizes[0])
            self._add(self.anon, name, t_s, sizes[1])

    @staticmethod
    def _add(
        table: dict[str, list[tuple[float, int]]], name: str, t_s: float, value: int | None
    ) -> None:
        if value is not None:
            table.setdefault(name, []).append((t_s, value))


def keep_waiting(
    stop: threading.Event, run: ShowRun, session: object, jobs: Jobs, target: int
) -> None:
    """Submit corpus characters, round and round, whenever fewer than ``target`` wait."""
    corpus = itertools.cycle(CORPUS)
    index = 0
    while not stop.wait(1.0):
        waiting = sum(n for state, n in jobs.counts().items() if state in WAITING_STATES)
        for _ in range(max(0, target - waiting)):
            try:
                reply = submit_char(session, run, next(corpus), index)  # type: ignore[arg-type]
            except (TimeoutError, RuntimeError) as exc:  # counted: the queue may run dry
                print(f"  submission {index} failed: {exc}", flush=True)
                break
            finally:
                index += 1
            jobs.submitted(str(reply.job_id), str(reply.state))


@dataclass(frozen=True)
class Pictures:
    """The job pictures of a run, read from the job directories."""

    jobs: int
    """Job directories with their ``metrics.json`` (pruned ones are not counted)."""
    waiting: int
    """Of them, those whose picture is ordered but not drawn yet."""
    late_s: list[tuple[float, float]]
    """Per drawn picture, oldest job first: when its job was recorded (``metrics.json``'s
    mtime, epoch [s]) and how much later in [s] its ``report.png`` was written."""

    @classmethod
    def of(cls, jobs_dir: Path) -> Pictures:
        jobs, waiting, late = 0, 0, []
        for job in jobs_dir.glob("*/metrics.json"):
            try:
                done_s = job.stat().st_mtime
                jobs += 1
                if (job.parent / "picture.order").exists():
                    waiting += 1
                elif (picture := job.parent / "report.png").exists():
                    late.append((done_s, picture.stat().st_mtime - done_s))
            except FileNotFoundError:
                continue  # pruned meanwhile
        return cls(jobs, waiting, sorted(late))


PICTURE_STALL_S = 180.0
"""Waiting for pictures stops when none was drawn for this long in [s]: an idle agent's planning
worker stops after 120 s (``vehicle_agent/worker_client.py``), the orders it left are drawn at
the vehicle's next job."""


def wait_for_pictures(jobs_dir: Path, timeout_s: float) -> tuple[Pictures, float]:
    """The pictures once none waits (or none was drawn for ``PICTURE_STALL_S``, or after
    ``timeout_s``), and the seconds waited."""
    start = progress = time.monotonic()
    pictures = Pictures.of(jobs_dir)
    while pictures.waiting and time.monotonic() - start < timeout_s:
        time.sleep(2.0)
        before, pictures = pictures.waiting, Pictures.of(jobs_dir)
        if pictures.waiting < before:
            progress = time.monotonic()
        elif time.monotonic() - progress > PICTURE_STALL_S:
            break
    return pictures, time.monotonic() - start


def traced(
    trace_dir: Path | None, names: list[str], period_s: float
) -> Callable[[ChildSpec], ChildSpec] | None:
    """Run the processes ``names`` (``orchestrator``, ``uav1``...) under ``memtrace.py``,
    reporting into ``trace_dir``."""
    if trace_dir is None:
        return None
    trace_dir.mkdir(parents=True, exist_ok=True)

    def adjust(spec: ChildSpec) -> ChildSpec:
        if spec.name.removeprefix("agent ") not in names:
            return spec
        out = trace_dir / f"{spec.name.removeprefix('agent ')}.txt"
        python, *rest = spec.argv
        tracer = (python, str(HERE / "memtrace.py"), str(out), repr(period_s))
        return replace(spec, argv=(*tracer, *rest))

    return adjust


def soak(
    args: argparse.Namespace, out_dir: Path
) -> tuple[Samples, Jobs, dict[str, int], Pictures, float]:
    """Run the show for ``args.minutes``; the samples, the jobs, restarts per process, the job
    pictures and how long in [s] the show ran on for the last ones."""
    path, show = derived_show(SHOW, out_dir, time_scale=args.time_scale)
    if args.database_budget_mb is not None:
        storage = show.storage.model_copy(update={"database_budget_mb": args.database_budget_mb})
        path, show = derived_show(path, out_dir, storage=storage)
    samples, jobs = Samples(), Jobs()
    adjust = traced(args.trace_memory, args.trace.split(","), args.warmup_minutes * 60.0)
    with (
        ShowRun(path, show, log_dir=out_dir / "logs", adjust=adjust) as run,
        run.client() as session,
        Stagehand(session, run.keys, period_s=5.0),
    ):
        _sub = subscribe(session, run.keys.jobs_all, JobState, jobs.on_job)
        wait_ready(run, session, len(show.vehicles), timeout_s=180.0)
        stop = threading.Event()
        feeder = threading.Thread(
            target=keep_waiting, args=(stop, run, session, jobs, args.waiting), daemon=True
        )
        start = time.monotonic()
        samples.take(0.0, run, show, jobs)
        feeder.start()
        end = start + args.minutes * 60.0
        next_print = start + 60.0
        while (now := time.monotonic()) < end:
            time.sleep(min(args.sample_s, end - now))
            samples.take(time.monotonic() - start, run, show, jobs)
            if time.monotonic() >= next_print:
                next_print += 60.0
                progress(samples, jobs)
        stop.set()
        feeder.join(timeout=30.0)
        pictures = wait_for_pictures(show.database_path.parent / "jobs", args.picture_wait_s)
        restarts = {name: run.supervisor.restarts(name) for name in run.supervisor.names}
    return samples, jobs, restarts, *pictures


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--minutes", type=float, default=60.0, help="length of the soak (60)")
    parser.add_argument("--time-scale", type=float, default=4.0, help="show time_scale (4)")
    parser.add_argument("--warmup-minutes", type=float, help="default: minutes/2, at most 25")
    parser.add_argument("--waiting", type=int, default=8, help="characters kept waiting (8)")
    parser.add_argument("--sample-s", type=float, default=10.0, help="sampling period (10 s)")
    parser.add_argument("--png", type=Path, help="plot RSS over time per process here")
    parser.add_argument(
        "--database-budget-mb",
        type=float,
        help="the show's storage.database_budget_mb (default: the show's; small to see the"
        " database compacted within a short run)",
    )
    parser.add_argument(
        "--picture-wait-s",
        type=float,
        default=600.0,
        help="after the soak, how long the show runs on for pictures still waiting (600 s)",
    )
    parser.add_argument("--out-dir", type=Path, help="keep the show's files here (default: tmp)")
    parser.add_argument(
        "--trace-memory",
        type=Path,
        metavar="DIR",
        help="run --trace processes under tracemalloc (slower): what grew after warm-up, by"
        " allocation site, in DIR/<process>.txt",
    )
    parser.add_argument(
        "--trace",
        default="orchestrator",
        help="processes to trace, comma-separated (orchestrator; agents slow the show: uav1...)",
    )
    args = parser.parse_args()
    if args.warmup_minutes is None:
        args.warmup_minutes = min(25.0, args.minutes / 2.0)
    if args.out_dir is not None:
        args.out_dir.mkdir(parents=True, exist_ok=True)
        samples, jobs, restarts, pictures, waited_s = soak(args, args.out_dir)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            samples, jobs, restarts, pictures, waited_s = soak(args, Path(tmp))
    report(args, samples, jobs, restarts)
    report_pictures(pictures, waited_s)
    if args.png is not None:
        plot(samples, args.png, args.warmup_minutes * 60.0)
        print(f"  RSS plot: {args.png}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
