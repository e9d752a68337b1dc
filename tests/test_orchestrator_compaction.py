"""Bounded SQLite history (issue 15): old finished jobs compacted, old events deleted, the file
kept under its budget; counts, idempotency keys and unfinished jobs untouched, across restarts;
a schema-3 database migrated in place."""

from __future__ import annotations

import asyncio
import os
import sqlite3
import tempfile
from collections import Counter
from pathlib import Path

import msgspec
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from bus.messages import Event, JobMetrics, SubmitRequest, WrittenInk
from orchestrator.compaction import CompactionSchedule, HistoryPolicy, compacted, used_bytes
from orchestrator.jobs import Job
from orchestrator.service import OrchestratorService
from orchestrator.store import JobStore, KeyedJob
from showfile import load_show

ROOT = Path(__file__).resolve().parents[1]
SHOW = load_show(ROOT / "shows" / "solo.yaml")
STROKES = {"v": 1, "strokes": [[[0.1 * k, 0.2 * k] for k in range(200)]]}
"""A drawn job's strokes document (a few kB of JSON)."""
UNFINISHED = ("awaiting_approval", "queued", "assigned", "writing")


def _ink(seed: int) -> WrittenInk:
    """A 160x160 picture (3.2 kB of bits, ~4.3 kB of JSON) as a vehicle reports it."""
    bits = bytes((seed * 31 + k * 7) % 256 for k in range(160 * 160 // 8))
    return WrittenInk(width_px=160, height_px=160, extent_m_board=(-0.5, -0.5, 0.5, 0.5), bits=bits)


def _job(seq: int, state: str, at_s: float, *, drawn: bool = False) -> Job:
    metrics = None
    if state == "done":
        metrics = JobMetrics(
            rmse_pen_down_m=0.002, rmse_m=0.003, max_error_m=0.006, iou=0.9, duration_s=13.0
        )
    return Job(
        job_id=f"j{seq}",
        seq=seq,
        state=state,  # type: ignore[arg-type]
        kind="strokes" if drawn else "text",
        text=None if drawn else "永",
        strokes=STROKES if drawn else None,
        label="drawing (1 strokes)" if drawn else "永",
        client_id="kiosk-1",
        created_at_s=at_s,
        updated_at_s=at_s + 30.0,
        vehicle_id="uav1",
        metrics=metrics,
        idempotency_key=f"k-{seq}",
    )


def _events(job: Job) -> list[Event]:
    """The log lines of a job's life (submitted, assigned, writing, and done if it is final)."""
    times = {"job_submitted": 0.0, "job_assigned": 1.0, "job_writing": 2.0}
    events = [
        Event(time_s=job.created_at_s + dt, level="info", kind=kind, message="x" * 80)
        for kind, dt in times.items()
    ]
    if job.final:
        events.append(Event(time_s=job.updated_at_s, level="info", kind="job_done", message="x"))
    return [msgspec.structs.replace(e, job_id=job.job_id) for e in events]


def _fill(store: JobStore, jobs: list[Job]) -> None:
    written = {job.job_id: _ink(job.seq) for job in jobs if job.state == "done"}
    store.save(jobs, [e for job in jobs for e in _events(job)], written=written)


def _compact_all(store: JobStore, policy: HistoryPolicy, now_s: float) -> None:
    """Call as the service does: again while work is left."""
    result = store.compact(policy, now_s)
    while result.more:
        result = store.compact(policy, now_s, resume=True)


def _file_bytes(path: Path) -> int:
    with sqlite3.connect(path) as db:  # the WAL checkpointed: the file as it stays
        db.execute("PRAGMA wal_checkpoint(TRUNCATE)")
    return os.path.getsize(path)


@settings(
    max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    states=st.lists(
        st.sampled_from(["done", "done", "done", "failed", "cancelled", *UNFINISHED]),
        min_size=100,
        max_size=400,
    ),
    drawn=st.sets(st.integers(1, 400), max_size=40),
    budget_kb=st.integers(60, 1000),
)
def test_the_database_stays_under_budget_and_loses_nothing(
    states: list[str], drawn: set[int], budget_kb: int
) -> None:
    jobs = [
        _job(seq, state, 1000.0 + 60.0 * seq, drawn=seq in drawn)
        for seq, state in enumerate(states, 1)
    ]
    policy = HistoryPolicy(budget_kb * 1000, keep_full_finished=5, keep_records=20, batch_jobs=20)
    now_s = 1000.0 + 60.0 * len(jobs) + 100.0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "s.sqlite3"
        with JobStore(path) as store:
            _fill(store, jobs)
            event("over budget" if used_bytes(store._db) > policy.budget_bytes else "within")
            _compact_all(store, policy, now_s)
            under_budget = used_bytes(store._db) <= policy.budget_bytes
            event("under budget after" if under_budget else "only the kept-forever left")
            event(
                "some folded"
                if store._db.execute("SELECT * FROM job_totals").fetchall()
                else "none folded"
            )
            if not under_budget:
                _check_only_the_kept_forever_left(store, jobs, policy)
            _check_nothing_lost(store, jobs)
        assert _file_bytes(path) <= policy.budget_bytes or not under_budget  # pages given back
        with JobStore(path) as store:  # and after a restart
            _check_nothing_lost(store, jobs)


def _check_only_the_kept_forever_left(
    store: JobStore, jobs: list[Job], policy: HistoryPolicy
) -> None:
    """Over budget: every finished job but the newest is folded (the newest records compacted),
    and no event is left from before the oldest unfinished job's submission."""
    finished = [j for j in jobs if j.final][: -policy.keep_full_finished]
    folded = finished[: -(policy.keep_records - policy.keep_full_finished)]
    assert all(store.job(j.job_id) is None for j in folded)
    assert all(store.job(j.job_id) == compacted(j) for j in finished[len(folded) :])
    oldest = min((j.created_at_s for j in jobs if not j.final), default=float("inf"))
    assert all(e.time_s >= oldest for e in store.events(limit=100_000))


def _check_nothing_lost(store: JobStore, jobs: list[Job]) -> None:
    assert store.load().job_counts == Counter(j.state for j in jobs)
    stored_events = Counter(e.job_id for e in store.events(limit=100_000))
    for job in jobs:
        if not job.final:  # an unfinished job's log lines stay
            assert stored_events[job.job_id] == len(_events(job))
    for job in jobs:
        stored = store.job(job.job_id)
        assert stored in (job, compacted(job), None)  # None: folded
        if not job.final:
            assert stored == job  # never touched
        assert store.job_by_key("kiosk-1", f"k-{job.seq}") == KeyedJob(job.job_id, job.state)
    newest_done = [j.job_id for j in [j for j in jobs if j.final][-5:] if j.state == "done"]
    assert set(store.written(newest_done)) == set(newest_done)  # the newest stay whole


def test_compaction_drops_the_bulky_parts_of_old_finished_jobs_only(tmp_path: Path) -> None:
    jobs = [_job(seq, "done", 60.0 * seq, drawn=seq % 2 == 0) for seq in range(1, 201)]
    jobs.insert(3, _job(201, "queued", 100.0, drawn=True))  # submitted long ago, still waiting
    with JobStore(tmp_path / "s.sqlite3") as store:
        _fill(store, jobs)
        before = used_bytes(store._db)
        policy = HistoryPolicy(budget_bytes=before - 1, keep_full_finished=10)
        _compact_all(store, policy, now_s=20_000.0)
        after = used_bytes(store._db)
        assert after <= policy.low_water_bytes
        old = store.job("j2")
        assert old == compacted(jobs[1]) and old is not None and old.strokes is None
        assert store.written(["j1", "j2"]) == {}
        assert store.job("j201") == jobs[3]  # unfinished: whole
        newest = [f"j{seq}" for seq in range(191, 201)]
        assert set(store.written(newest)) == set(newest)
        assert store.job("j200") == jobs[-1]
        # events since the waiting job's submission stay, so do all its own
        assert min(e.time_s for e in store.events(limit=10_000)) >= 100.0
        assert any(e.job_id == "j201" for e in store.events(limit=10_000))


def test_under_budget_without_an_age_limit_nothing_changes(tmp_path: Path) -> None:
    jobs = [_job(seq, "done", 60.0 * seq) for seq in range(1, 30)]
    with JobStore(tmp_path / "s.sqlite3") as store:
        _fill(store, jobs)
        result = store.compact(HistoryPolicy(budget_bytes=10_000_000), now_s=1e9)
        assert (result.jobs, result.events) == (0, 0)
        assert store.job("j1") == jobs[0] and len(store.events(limit=1000)) == 4 * len(jobs)


def test_the_age_limit_compacts_what_finished_before_it(tmp_path: Path) -> None:
    jobs = [_job(seq, "done", 3600.0 * seq) for seq in range(1, 11)]
    with JobStore(tmp_path / "s.sqlite3") as store:
        _fill(store, jobs)
        policy = HistoryPolicy(budget_bytes=10_000_000, max_age_s=4 * 3600.0, keep_full_finished=1)
        store.compact(policy, now_s=10.5 * 3600.0)  # finished before 6.5 h: j1..j6
        assert set(store.written([j.job_id for j in jobs])) == {"j7", "j8", "j9", "j10"}
        assert min(e.time_s for e in store.events(limit=1000)) >= 6.5 * 3600.0


def test_a_folded_jobs_idempotency_key_still_answers_it(tmp_path: Path) -> None:
    jobs = [_job(seq, "done", 60.0 * seq, drawn=True) for seq in range(1, 601)]
    with JobStore(tmp_path / "s.sqlite3") as store:
        _fill(store, jobs)
        _compact_all(store, HistoryPolicy(budget_bytes=1, keep_full_finished=10), now_s=1e6)
        assert store.job("j100") is None and store.job("j101") == compacted(jobs[100])  # folded
        service = OrchestratorService(SHOW, session=None, store=store)  # type: ignore[arg-type]
        assert "j1" not in service.book.jobs  # past the finished jobs held in memory
        request = SubmitRequest(text="永", client_id="kiosk-1", idempotency_key="k-1")
        reply = asyncio.run(service.on_submit(request))
        assert reply.ok and reply.job_id == "j1" and reply.state == "done"
        assert store.load().job_counts == {"done": 600}


_SCHEMA_3 = """
CREATE TABLE jobs (job_id TEXT PRIMARY KEY, seq INTEGER NOT NULL UNIQUE, state TEXT NOT NULL,
    data BLOB NOT NULL, idempotency_key TEXT, written BLOB);
CREATE INDEX jobs_state ON jobs (state);
CREATE UNIQUE INDEX jobs_idempotency_key ON jobs (idempotency_key)
    WHERE idempotency_key IS NOT NULL;
CREATE TABLE events (id INTEGER PRIMARY KEY AUTOINCREMENT, time_s REAL NOT NULL,
    data BLOB NOT NULL);
CREATE TABLE settings (key TEXT PRIMARY KEY, value TEXT NOT NULL);
PRAGMA user_version=3;
"""  # fmt: skip


def test_a_schema_3_database_migrates_in_place(tmp_path: Path) -> None:
    path = tmp_path / "s.sqlite3"
    jobs = [_job(seq, "done", 60.0 * seq) for seq in range(1, 101)] + [_job(101, "queued", 6000.0)]
    with sqlite3.connect(path) as db:
        db.execute("PRAGMA journal_mode=WAL")
        db.executescript(_SCHEMA_3)
        db.executemany(
            "INSERT INTO jobs (job_id, seq, state, data, idempotency_key, written) "
            "VALUES (?, ?, ?, ?, ?, ?)",
            [
                (j.job_id, j.seq, j.state, msgspec.json.encode(j), f"kiosk-1\x1fk-{j.seq}",
                 msgspec.json.encode(_ink(j.seq)) if j.final else None)
                for j in jobs
            ],
        )  # fmt: skip
        db.executemany(
            "INSERT INTO events (time_s, data) VALUES (?, ?)",
            [(e.time_s, msgspec.json.encode(e)) for j in jobs for e in _events(j)],
        )
        assert db.execute("PRAGMA auto_vacuum").fetchone()[0] == 0  # none
    with JobStore(path) as store:
        assert store._db.execute("PRAGMA user_version").fetchone()[0] == 4
        assert store._db.execute("PRAGMA auto_vacuum").fetchone()[0] == 2  # incremental
        _check_nothing_lost(store, jobs)
        _compact_all(store, HistoryPolicy(budget_bytes=200_000, keep_full_finished=5), 1e6)
        _check_nothing_lost(store, jobs)
        assert store.job("j1") == compacted(jobs[0]) and store.written(["j1"]) == {}
    assert _file_bytes(path) <= 200_000


def test_a_saved_job_counts_as_whole_again(tmp_path: Path) -> None:
    """A compacted row written again (a job's new version) is a candidate for compaction again."""
    with JobStore(tmp_path / "s.sqlite3") as store:
        jobs = [_job(seq, "done", 60.0 * seq, drawn=True) for seq in range(1, 4)]
        _fill(store, jobs)
        _compact_all(store, HistoryPolicy(budget_bytes=1, keep_full_finished=1), now_s=1e6)
        store.save([jobs[0]])
        assert store.job("j1") == jobs[0]
        _compact_all(store, HistoryPolicy(budget_bytes=1, keep_full_finished=1), now_s=1e6)
        assert store.job("j1") == compacted(jobs[0])


def test_the_schedule_compacts_at_start_then_every_n_finished_jobs() -> None:
    schedule = CompactionSchedule(every_finished=50, period_s=600.0)
    assert schedule.due(0.0)  # at start
    schedule.ran(0.0, more=False)
    schedule.finished += 49
    assert not schedule.due(10.0)
    schedule.finished += 1
    assert schedule.due(10.0)
    schedule.ran(10.0, more=True)
    assert schedule.due(10.1)  # work left: at the next chance
    schedule.ran(10.1, more=False)
    assert not schedule.due(609.0) and schedule.due(610.1)


def test_the_service_compacts_at_start_and_when_due(tmp_path: Path) -> None:
    jobs = [_job(seq, "done", 60.0 * seq, drawn=True) for seq in range(1, 301)]
    with JobStore(tmp_path / "s.sqlite3") as store:
        _fill(store, jobs)
        service = OrchestratorService(SHOW, session=None, store=store)  # type: ignore[arg-type]
        assert service.history.budget_bytes == 100_000_000  # the show file's default
        service.history = HistoryPolicy(600_000, keep_full_finished=10)
        service.compact_history(1e6)  # at start: one batch, work left
        assert store.job("j50") == compacted(jobs[49]) and store.job("j51") == jobs[50]
        for tick in range(1, 8):  # the next ticks resume
            service.compact_history(1e6 + 0.1 * tick)
        assert store.job("j290") == compacted(jobs[289]) and store.job("j291") == jobs[290]
        assert used_bytes(store._db) <= 600_000
        store.save([jobs[0]])  # whole again, but too soon for another call
        service.compact_history(1e6 + 0.2)
        assert store.job("j1") == jobs[0]
