"""Durability: the SQLite store round-trips, and an acknowledged submission survives kill -9."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from bus.keys import ShowKeys
from bus.messages import ErrorInfo, Event, ShowSnapshot, SubmitReply, SubmitRequest
from bus.rpc import query, query_one
from bus.session import open_session
from orchestrator.core import Book
from orchestrator.jobs import Job, transition
from orchestrator.outputs import core_config
from orchestrator.store import JobStore, StoreError
from showfile import load_show

sys.path.insert(0, str(Path(__file__).parent))
from test_orchestrator_service import WAIT_S, eventually, make_show

ROOT = Path(__file__).resolve().parents[1]


def _job(job_id: str, seq: int) -> Job:
    return Job(
        job_id=job_id,
        seq=seq,
        state="queued",
        kind="text",
        text="永",
        label="永",
        client_id="kiosk-1",
        created_at_s=1.0,
        updated_at_s=1.0,
    )


def test_store_round_trip(tmp_path: Path) -> None:
    db = tmp_path / "s.sqlite3"
    j1, j2 = _job("j1", 1), _job("j2", 2)
    event = Event(time_s=2.0, level="info", kind="job_submitted", message="永", job_id="j1")
    with JobStore(db) as store:
        store.save([j1, j2], [event], queue_paused=True, paused_vehicles=["uav2"])
        failed = transition(j2, "failed", 3.0, error=ErrorInfo(code="x", message="y"))
        store.save([failed])
    with JobStore(db) as store:
        state = store.load()
        assert state.jobs == [j1, failed]
        assert state.queue_paused and state.paused_vehicles == ["uav2"]
        assert store.events() == [event]
        assert store.job("j2") == failed
        journal = store._db.execute("PRAGMA journal_mode").fetchone()[0]
        sync = store._db.execute("PRAGMA synchronous").fetchone()[0]
    assert (journal, sync) == ("wal", 2)  # 2 = FULL


def test_failed_transaction_leaves_nothing(tmp_path: Path) -> None:
    with JobStore(tmp_path / "s.sqlite3") as store:
        store.save([_job("j1", 1)])
        with pytest.raises(StoreError, match="UNIQUE"):
            store.save([_job("j2", 2), _job("j3", 1)])  # j3 reuses seq 1
        assert [j.job_id for j in store.load().jobs] == ["j1"]


def test_unknown_schema_version_is_refused(tmp_path: Path) -> None:
    db = tmp_path / "s.sqlite3"
    with JobStore(db) as store:
        store._db.execute("PRAGMA user_version=99")
    with pytest.raises(StoreError, match="schema version 99"):
        JobStore(db)


def test_restored_book_has_the_same_jobs(tmp_path: Path) -> None:
    show = load_show(ROOT / "shows" / "solo.yaml")
    book = Book(core_config(show), now_s=0.0)
    _, eff = book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=3, now_s=0)
    with JobStore(tmp_path / "s.sqlite3") as store:
        store.save(eff.jobs.values(), eff.events)
    with JobStore(tmp_path / "s.sqlite3") as store:
        again = Book(core_config(show), store.load().jobs, now_s=5.0)
    assert again.jobs == book.jobs and again.next_seq == book.next_seq


def _start(path: Path) -> subprocess.Popen[bytes]:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "cli.main", "orchestrator", str(path), "--role", "router"],
        cwd=ROOT,
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
    )


@pytest.mark.slow
@pytest.mark.multiprocess
@pytest.mark.timeout(120)
def test_acknowledged_submission_survives_kill_9_and_restart(
    tmp_path: Path, free_tcp_port: object
) -> None:
    path, show = make_show(tmp_path, "durable", f"tcp/127.0.0.1:{free_tcp_port()}")  # type: ignore[operator]
    keys = ShowKeys(show.show_id)
    proc = _start(path)
    try:
        with open_session(show.zenoh, role="client", open_timeout_s=WAIT_S) as client:
            eventually(lambda: query(client, keys.snapshot, None, ShowSnapshot, timeout_s=0.5))
            acked = [
                query_one(client, keys.submit, SubmitRequest(text=t), SubmitReply)
                for t in ("一", "二")
            ]
            last = query_one(client, keys.submit, SubmitRequest(text="三"), SubmitReply)
            proc.send_signal(signal.SIGKILL)  # right after the acknowledgement
            proc.wait(WAIT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
    acked.append(last)
    assert all(r.ok for r in acked)
    with JobStore(show.database_path) as store:
        stored = {j.job_id: j for j in store.load().jobs}
    assert [stored[r.job_id or ""].label for r in acked] == ["一", "二", "三"]
    assert all(stored[r.job_id or ""].state == "queued" for r in acked)
    proc = _start(path)
    try:
        with open_session(show.zenoh, role="client", open_timeout_s=WAIT_S) as client:
            snap = eventually(
                lambda: query(client, keys.snapshot, None, ShowSnapshot, timeout_s=0.5)
            )[0].value
            assert snap is not None
            assert [j.job_id for j in snap.jobs] == [r.job_id for r in acked]
            assert [j.queue_position for j in snap.jobs] == [1, 2, 3]
    finally:
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(WAIT_S) == 0
