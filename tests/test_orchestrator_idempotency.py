"""Idempotent submissions: a repeated key gets the same job, in memory, in SQLite, across a hang.

The multi-process test freezes the real orchestrator (SIGSTOP) while a client submits with a key
and times out, sends the same request again, then thaws it: every request queued during the hang
is answered, and exactly one job exists.
"""

from __future__ import annotations

import signal
import sqlite3
import sys
from pathlib import Path

import msgspec
import pytest

from bus.keys import ShowKeys
from bus.messages import ShowSnapshot, SubmitReply, SubmitRequest
from bus.rpc import NoReplyError, RemoteError, query, query_one
from bus.session import open_session
from orchestrator.core import Book
from orchestrator.jobs import Job
from orchestrator.outputs import core_config
from orchestrator.store import SCHEMA_VERSION, JobStore, StoreError
from showfile import load_show

sys.path.insert(0, str(Path(__file__).parent))
from test_orchestrator_service import WAIT_S, eventually, make_show
from test_orchestrator_store import _start

ROOT = Path(__file__).resolve().parents[1]

V1_SCHEMA = """
CREATE TABLE jobs (job_id TEXT PRIMARY KEY, seq INTEGER NOT NULL UNIQUE, state TEXT NOT NULL,
                   data BLOB NOT NULL);
CREATE INDEX jobs_state ON jobs (state);
CREATE TABLE events (id INTEGER PRIMARY KEY AUTOINCREMENT, time_s REAL NOT NULL,
                     data BLOB NOT NULL);
CREATE TABLE settings (key TEXT PRIMARY KEY, value TEXT NOT NULL);
PRAGMA user_version=1;
"""


def _book() -> Book:
    return Book(core_config(load_show(ROOT / "shows" / "solo.yaml")), now_s=0.0)


def _submit(book: Book, job_id: str, key: str | None, client: str = "kiosk-1") -> SubmitReply:
    request = SubmitRequest(text="永", client_id=client, idempotency_key=key)
    reply, _ = book.submit(job_id, request, label="永", estimate_s=5.0, now_s=1.0)
    return reply


def test_a_repeated_key_gets_the_same_job_and_reply() -> None:
    book = _book()
    first = _submit(book, "j1", "k-1")
    again = _submit(book, "j2", "k-1")
    assert first.ok and again == first and again.job_id == "j1"
    assert list(book.jobs) == ["j1"]
    # another key, or the same key from another client, is another submission
    assert _submit(book, "j3", "k-2").job_id == "j3"
    assert _submit(book, "j4", "k-1", client="kiosk-2").job_id == "j4"
    assert _submit(book, "j5", None).job_id == "j5"
    assert _submit(book, "j6", None).job_id == "j6"


def test_key_longer_than_64_characters_is_refused_on_the_wire() -> None:
    raw = msgspec.json.encode({"text": "A", "idempotency_key": "k" * 65})
    with pytest.raises(msgspec.ValidationError, match="idempotency_key"):
        msgspec.json.decode(raw, type=SubmitRequest)


def test_keys_survive_a_restart_through_the_store(tmp_path: Path) -> None:
    book = _book()
    request = SubmitRequest(text="永", client_id="kiosk-1", idempotency_key="k-1")
    _, eff = book.submit("j1", request, label="永", estimate_s=5.0, now_s=1.0)
    with JobStore(tmp_path / "s.sqlite3") as store:
        store.save(eff.jobs.values(), eff.events)
    with JobStore(tmp_path / "s.sqlite3") as store:
        restarted = Book(book.config, store.load().jobs, now_s=9.0)
        assert _submit(restarted, "j2", "k-1").job_id == "j1"
        # the database itself refuses a second job with the same client and key
        twin = msgspec.structs.replace(book.jobs["j1"], job_id="j2", seq=2)
        with pytest.raises(StoreError, match="UNIQUE"):
            store.save([twin])


def test_a_version_1_database_is_migrated_in_place(tmp_path: Path) -> None:
    db = tmp_path / "old.sqlite3"
    old = Job(
        job_id="j1", seq=1, state="queued", kind="text", text="A", label="A",
        client_id="cli", created_at_s=1.0, updated_at_s=1.0,
    )  # fmt: skip
    with sqlite3.connect(db) as conn:
        conn.executescript(V1_SCHEMA)
        data = msgspec.json.encode(old)
        conn.execute("INSERT INTO jobs VALUES ('j1', 1, 'queued', ?)", (data,))
    with JobStore(db) as store:
        assert store.load().jobs == [old]
        version = store._db.execute("PRAGMA user_version").fetchone()[0]
        keyed = msgspec.structs.replace(old, job_id="j2", seq=2, idempotency_key="k")
        store.save([keyed])
    assert version == SCHEMA_VERSION == 4
    with JobStore(db) as store:  # opening a current database again changes nothing
        assert [j.idempotency_key for j in store.load().jobs] == [None, "k"]


@pytest.mark.slow
@pytest.mark.multiprocess
@pytest.mark.timeout(90)
def test_retries_during_a_hang_make_one_job(tmp_path: Path, free_tcp_port: object) -> None:
    path, show = make_show(tmp_path, "hang", f"tcp/127.0.0.1:{free_tcp_port()}")  # type: ignore[operator]
    keys = ShowKeys(show.show_id)
    request = SubmitRequest(text="永", client_id="kiosk-9", idempotency_key="visit-1")
    proc = _start(path)
    try:
        with open_session(show.zenoh, role="client", open_timeout_s=WAIT_S) as client:
            eventually(lambda: query(client, keys.snapshot, None, ShowSnapshot, timeout_s=0.5))
            proc.send_signal(signal.SIGSTOP)
            for _ in range(2):  # the visitor's tries while the orchestrator is frozen
                with pytest.raises((NoReplyError, RemoteError)):  # no answer, or zenoh's timeout
                    query_one(client, keys.submit, request, SubmitReply, timeout_s=1.0)
            proc.send_signal(signal.SIGCONT)
            # the frozen link was dropped (2 s lease); retry as the kiosk does until answered
            answers = eventually(
                lambda: [r.value for r in query(client, keys.submit, request, SubmitReply)
                         if r.value is not None],
                "an answer after the thaw",
            )  # fmt: skip
            reply = answers[0]
            assert reply.ok and reply.job_id is not None
            again = query_one(client, keys.submit, request, SubmitReply, timeout_s=WAIT_S)
            assert again.job_id == reply.job_id
            snap = query_one(client, keys.snapshot, None, ShowSnapshot, timeout_s=WAIT_S)
            assert [j.job_id for j in snap.jobs] == [reply.job_id]
    finally:
        proc.send_signal(signal.SIGCONT)
        proc.send_signal(signal.SIGTERM)
        assert proc.wait(WAIT_S) == 0
