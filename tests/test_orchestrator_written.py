"""A done job's ink picture: kept apart from the job, stored with it, served where asked."""

from __future__ import annotations

import sqlite3
from pathlib import Path

import msgspec
import numpy as np
from test_orchestrator_core import METRICS, _config, _online, _submit
from test_orchestrator_idempotency import V1_SCHEMA

from bus.codec import MAX_PAYLOAD_BYTES, encode
from bus.messages import AgentReport, JobState, ShowSnapshot, WrittenInk
from orchestrator.core import Book
from orchestrator.jobs import Job
from orchestrator.store import SCHEMA_VERSION, JobStore
from orchestrator.written import attach_written, split_written, with_written

INK = WrittenInk(
    width_px=160, height_px=160, extent_m_board=(-0.72, -0.72, 0.72, 0.72),
    bits=np.packbits(np.eye(160, dtype=bool).ravel()).tobytes(),
)  # fmt: skip
V2_SCHEMA = V1_SCHEMA.replace("data BLOB NOT NULL);\nCREATE INDEX", "data BLOB NOT NULL,\n"
                              "idempotency_key TEXT);\nCREATE INDEX").replace(
    "user_version=1", "user_version=2")  # fmt: skip


def _done_book() -> tuple[Book, dict[str, WrittenInk]]:
    book = Book(_config(), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.5)
    book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="started"), 1.0)
    metrics = msgspec.structs.replace(METRICS, written=INK)
    report = AgentReport(vehicle_id="uav1", job_id="j1", event="done", metrics=metrics)
    reply, eff = book.report(report, 2.0)
    assert reply.ok
    again, later = book.report(report, 2.5)  # a retried report changes nothing
    assert again.ok and later.written == {} and later.jobs == {}
    return book, eff.written


def test_a_done_report_hands_the_picture_over_and_keeps_it_out_of_the_job() -> None:
    book, written = _done_book()
    job = book.jobs["j1"]
    assert written == {"j1": INK}
    assert job.state == "done" and job.metrics == METRICS and job.metrics.written is None
    snapshot = book.snapshot(3.0)
    assert all(j.metrics is None or j.metrics.written is None for j in snapshot.jobs)
    assert split_written(None) == (None, None)


def test_the_picture_is_stored_with_its_job_and_read_back(tmp_path: Path) -> None:
    book, written = _done_book()
    with JobStore(tmp_path / "s.sqlite3") as store:
        store.save(book.jobs.values(), written=written)
        assert store.written(["j1", "nope"]) == {"j1": INK}
        assert store.load().jobs == list(book.jobs.values())


def test_a_version_2_database_gets_the_column_in_place(tmp_path: Path) -> None:
    db = tmp_path / "old.sqlite3"
    old = Job(
        job_id="j1", seq=1, state="done", kind="text", text="A", label="A",
        client_id="cli", created_at_s=1.0, updated_at_s=1.0, metrics=METRICS,
    )  # fmt: skip
    with sqlite3.connect(db) as conn:
        conn.executescript(V2_SCHEMA)
        conn.execute(
            "INSERT INTO jobs VALUES ('j1', 1, 'done', ?, NULL)", (msgspec.json.encode(old),)
        )
    with JobStore(db) as store:
        assert store.load().jobs == [old] and store.written(["j1"]) == {}
        store.save(written={"j1": INK})
        version = store._db.execute("PRAGMA user_version").fetchone()[0]
    assert version == SCHEMA_VERSION == 4
    with JobStore(db) as store:
        assert store.written(["j1"]) == {"j1": INK}


def _done_state(job_id: str) -> JobState:
    return JobState(
        job_id=job_id, state="done", label="A", kind="text", client_id="c",
        created_at_s=1.0, updated_at_s=2.0, metrics=METRICS,
    )  # fmt: skip


def test_a_snapshot_carries_the_newest_pictures_within_its_budget() -> None:
    ids = [f"j{i}" for i in range(300)]
    queued = msgspec.structs.replace(_done_state("q"), state="queued", metrics=None)
    snapshot = ShowSnapshot(
        show_id="t", time_s=0.0, queue_paused=False,
        jobs=[*map(_done_state, ids), queued], vehicles=[],
    )  # fmt: skip
    stored = dict.fromkeys(ids, INK)
    budget = 10 * len(encode(INK)) + 100
    out = attach_written(snapshot, lambda wanted: {i: stored[i] for i in wanted}, budget)
    pictured = [j.job_id for j in out.jobs if j.metrics is not None and j.metrics.written]
    assert pictured == ids[-10:]  # the ten newest, in their places
    assert [j.job_id for j in out.jobs] == [j.job_id for j in snapshot.jobs]
    everything = attach_written(snapshot, lambda wanted: {i: stored[i] for i in wanted}, 10**9)
    assert len(encode(everything)) > MAX_PAYLOAD_BYTES  # why a budget is needed
    assert attach_written(snapshot, lambda wanted: {}, budget) == snapshot
    assert with_written(queued, INK) == queued  # no metrics, nothing to attach to
