"""What a finished job costs in the orchestrator's SQLite database, and what compacting costs.

    python benchmarks/bench_store.py                      # synthetic 10,000 finished jobs
    python benchmarks/bench_store.py --db out/soak/show.sqlite3   # also: bytes per job of a show

``--db``: bytes per finished job by table and column of a show's database (opened read-only):
``jobs.data`` by field, ``jobs.written`` (ink pictures), events per job by kind.

Then, on a synthetic database of ``--jobs`` done text jobs as the Airshow soak leaves them (a
4.3 kB ink picture, metrics, four events each): the time of one compaction call (the work the
service does in one timer tick, ``max_batches`` transactions) and of one batch, against the
peer measured in the same run: one decision's transaction (a submission saved, fsynced), which
every reply waits for anyway. Also the one-off migration of a schema-3 file of that size
(``VACUUM`` into incremental auto-vacuum) and the file's size before and after compaction.
"""

from __future__ import annotations

import argparse
import json
import sqlite3
import statistics
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from bus.messages import Event, JobMetrics, WrittenInk  # noqa: E402
from orchestrator.compaction import HistoryPolicy, used_bytes  # noqa: E402
from orchestrator.jobs import Job  # noqa: E402
from orchestrator.store import JobStore  # noqa: E402


def measure(db_path: Path) -> None:
    """Print bytes per finished job by table and column of a show's database."""
    db = sqlite3.connect(f"file:{db_path}?mode=ro", uri=True)
    finished = db.execute(
        "SELECT COUNT(*) FROM jobs WHERE state IN ('done','failed','cancelled','rejected')"
    ).fetchone()[0]
    pages = db.execute("PRAGMA page_count").fetchone()[0] * 4096
    print(f"{db_path}: {pages / 1e6:.2f} MB of pages, {finished} finished jobs")
    fields: Counter[str] = Counter()
    ink = data = 0
    for raw, written in db.execute("SELECT data, written FROM jobs"):
        data += len(raw)
        ink += len(written or b"")
        for name, value in json.loads(raw).items():
            fields[name] += len(json.dumps(value, separators=(",", ":")))
    per = max(1, finished)
    print(f"  jobs.written (ink picture) {ink / per:7.0f} B/job")
    print(f"  jobs.data                  {data / per:7.0f} B/job, of which:")
    for name, size in fields.most_common(5):
        print(f"    {name:24} {size / per:7.0f} B/job")
    kinds: Counter[str] = Counter()
    event_bytes = 0
    for (raw,) in db.execute("SELECT data FROM events"):
        kinds[json.loads(raw)["kind"]] += 1
        event_bytes += len(raw)
    print(
        f"  events                     {event_bytes / per:7.0f} B/job"
        f" ({sum(kinds.values()) / per:.1f} rows/job: {dict(kinds.most_common(4))})"
    )
    try:
        rows = db.execute("SELECT name, SUM(pgsize) FROM dbstat GROUP BY name ORDER BY 2 DESC")
        print("  pages by table/index: " + ", ".join(f"{n} {b / per:.0f} B/job" for n, b in rows))
    except sqlite3.OperationalError:
        pass  # SQLite built without dbstat


def synthetic(n_jobs: int) -> tuple[list[Job], list[Event], dict[str, WrittenInk]]:
    """``n_jobs`` done text jobs a minute apart with their ink pictures and four events."""
    metrics = JobMetrics(
        rmse_pen_down_m=0.002, rmse_m=0.0023, max_error_m=0.0057, iou=0.915, duration_s=13.4,
        extra={"max_error_pen_down_m": 0.0046, "rmse_pen_down_xy_m": 0.0019,
               "ink_intersection_ratio": 0.937, "ink_union_ratio": 1.024, "sim_time_s": 13.4},
    )  # fmt: skip
    jobs, events, inks = [], [], {}
    for k in range(n_jobs):
        t = 1.7e9 + 60.0 * k
        job = Job(
            job_id=f"j{k:012x}", seq=k + 1, state="done", kind="text", text="永", label="永",
            client_id="bench", created_at_s=t, updated_at_s=t + 40.0, vehicle_id="uav1",
            board_id="b1", assigned_at_s=t, attempts=1, estimate_s=13.4,
            planned_duration_s=13.4, progress=1.0, metrics=metrics, idempotency_key=f"k-{k}",
        )  # fmt: skip
        jobs.append(job)
        bits = bytes((k * 31 + i * 7) % 256 for i in range(160 * 160 // 8))
        inks[job.job_id] = WrittenInk(
            width_px=160, height_px=160, extent_m_board=(-0.5, -0.5, 0.5, 0.5), bits=bits
        )
        for dt, kind in ((0.0, "job_submitted"), (0.1, "job_assigned"), (5.0, "job_writing"),
                         (40.0, "job_done")):  # fmt: skip
            message = f"永 {kind} uav1 (attempt 1) " + "x" * 60
            events.append(
                Event(time_s=t + dt, level="info", kind=kind, message=message, job_id=job.job_id)
            )
    return jobs, events, inks


def timed(call: object) -> float:
    start = time.perf_counter()
    call()  # type: ignore[operator]
    return time.perf_counter() - start


def bench(n_jobs: int, repeats: int) -> None:
    jobs, events, inks = synthetic(n_jobs)
    phases = {  # budget 1 byte: everything allowed is done
        "compact": HistoryPolicy(budget_bytes=1, keep_records=n_jobs),
        "fold": HistoryPolicy(budget_bytes=1),
    }
    print(f"synthetic: {n_jobs} done jobs, {len(events)} events")
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "s.sqlite3"
        with JobStore(path) as store:
            store.save(jobs, events, written=inks)
            full = used_bytes(store._db)
            print(f"  database: {full / 1e6:.1f} MB full ({full / n_jobs:.0f} B/job)")
            peers = [
                timed(lambda k=k: store.save([_submission(k)])) for k in range(repeats)
            ]  # one decision each: a new job, one fsynced transaction
            peer = statistics.median(peers)
            print(f"  one decision's transaction (peer): median {peer * 1e3:.2f} ms over {repeats}")
            for name, policy in phases.items():
                calls = _until_done(store, policy)
                size = used_bytes(store._db)
                call = statistics.median(calls)
                print(
                    f"  {name}: {size / 1e6:.2f} MB after ({size / n_jobs:.0f} B/job);"
                    f" one call ({policy.max_batches} x {policy.batch_jobs} jobs):"
                    f" median {call * 1e3:.1f} ms, max {max(calls) * 1e3:.1f} ms"
                    f" ({call / peer:.1f}x the peer, {max(calls) / peer:.1f}x at most);"
                    f" {len(calls)} calls, {sum(calls):.2f} s in all"
                )


def _until_done(store: JobStore, policy: HistoryPolicy) -> list[float]:
    """Call compaction as the service does until no work is left; the time of each call."""
    calls: list[float] = []
    while True:
        start = time.perf_counter()
        result = store.compact(policy, 1.8e9, resume=bool(calls))
        calls.append(time.perf_counter() - start)
        if not result.more:
            return calls


def migration(jobs: list[Job], events: list[Event], inks: dict[str, WrittenInk]) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "s.sqlite3"
        _schema_3(path, jobs, events, inks)
        size = path.stat().st_size
        start = time.perf_counter()
        JobStore(path).close()
        print(
            f"  migration of a schema-3 file of {size / 1e6:.1f} MB (VACUUM once):"
            f" {time.perf_counter() - start:.2f} s"
        )


def _submission(k: int) -> Job:
    return Job(
        job_id=f"new{k}", seq=10_000_000 + k, state="queued", kind="text", text="永",
        label="永", client_id="bench", created_at_s=1.8e9, updated_at_s=1.8e9,
    )  # fmt: skip


def _schema_3(
    path: Path, jobs: list[Job], events: list[Event], inks: dict[str, WrittenInk]
) -> None:
    """A database as schema 3 left it: no auto-vacuum, no ``compacted`` column."""
    with JobStore(path) as store:
        store.save(jobs, events, written=inks)
    db = sqlite3.connect(path, isolation_level=None)
    db.execute("PRAGMA auto_vacuum=NONE")
    db.execute("DROP INDEX jobs_full_finished")
    db.execute("ALTER TABLE jobs DROP COLUMN compacted")
    db.execute("VACUUM")
    db.execute("PRAGMA user_version=3")
    db.close()


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--db", type=Path, help="a show's database: bytes per job")
    parser.add_argument("--jobs", type=int, default=10_000, help="synthetic jobs (10,000)")
    parser.add_argument("--repeats", type=int, default=30, help="peer transactions (30)")
    args = parser.parse_args()
    if args.db is not None:
        measure(args.db)
    bench(args.jobs, args.repeats)
    migration(*synthetic(args.jobs))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
