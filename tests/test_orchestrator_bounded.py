"""A long show keeps a bounded set of jobs in the orchestrator's memory (issue 15).

Finished jobs beyond ``MAX_FINAL_JOBS`` leave the Book (the database keeps them); a restart loads
only as many; a repeated idempotency key of a forgotten job still gets that job, from SQLite.
"""

from __future__ import annotations

import asyncio
from pathlib import Path
from typing import Any

import msgspec

from bus.messages import OperatorCommand, SubmitRequest
from orchestrator.core import MAX_FINAL_JOBS, Book
from orchestrator.estimates import CACHED_DURATIONS
from orchestrator.finished import FinishedJobs
from orchestrator.jobs import Job, transition
from orchestrator.kinds import KindPlans
from orchestrator.outputs import core_config
from orchestrator.service import OrchestratorService
from orchestrator.store import JobStore
from showfile import load_show

ROOT = Path(__file__).resolve().parents[1]
SHOW = load_show(ROOT / "shows" / "solo.yaml")


def _submit_and_cancel(book: Book, n: int, now_s: float = 1.0) -> None:
    """Submit ``n`` keyed jobs and cancel each (finished at once, no vehicle needed)."""
    for k in range(n):
        request = SubmitRequest(text="永", client_id="kiosk-1", idempotency_key=f"k-{k}")
        reply, _ = book.submit(f"j{k}", request, label="永", estimate_s=5.0, now_s=now_s)
        cancel = OperatorCommand(command="cancel", job_id=reply.job_id, operator="test")
        assert book.operator(cancel, now_s)[0].ok


def test_the_book_keeps_only_the_latest_finished_jobs() -> None:
    book = Book(core_config(SHOW), now_s=0.0)
    _submit_and_cancel(book, MAX_FINAL_JOBS + 40)
    assert len(book.jobs) == MAX_FINAL_JOBS
    assert "j39" not in book.jobs and "j40" in book.jobs  # the oldest went first
    assert len(book.by_key) == MAX_FINAL_JOBS
    assert book.job_counts["cancelled"] == MAX_FINAL_JOBS + 40  # counts stay whole
    assert book.snapshot(2.0).job_counts == {"cancelled": MAX_FINAL_JOBS + 40}


def test_unfinished_jobs_are_never_forgotten() -> None:
    book = Book(core_config(SHOW), now_s=0.0, max_final_jobs=2)
    waiting = SubmitRequest(text="A", client_id="kiosk-1")
    book.submit("first", waiting, label="A", estimate_s=5.0, now_s=1.0)
    _submit_and_cancel(book, 5)
    assert sorted(book.jobs) == ["first", "j3", "j4"]
    assert [j.job_id for j in book.queue()] == ["first"]


def _stored_jobs(n: int) -> list[Job]:
    """``n`` keyed jobs done long ago, then one queued."""
    done = [
        Job(
            job_id=f"j{k}", seq=k + 1, state="done", kind="text", text="永", label="永",
            client_id="kiosk-1", created_at_s=1.0, updated_at_s=2.0 + k,
            idempotency_key=f"k-{k}",
        )
        for k in range(n)
    ]  # fmt: skip
    queued = msgspec.structs.replace(
        done[0], job_id="late", seq=n + 1, state="queued", idempotency_key=None
    )
    return [*done, queued]


def test_a_restart_loads_the_unfinished_and_the_latest_finished_jobs(tmp_path: Path) -> None:
    with JobStore(tmp_path / "s.sqlite3") as store:
        store.save(_stored_jobs(20))
        stored = store.load(max_final=5)
    assert [j.job_id for j in stored.jobs] == ["j15", "j16", "j17", "j18", "j19", "late"]
    assert stored.job_counts == {"done": 20, "queued": 1}
    book = Book(core_config(SHOW), stored.jobs, now_s=50.0, job_counts=stored.job_counts)
    assert book.next_seq == 22 and book.job_counts["done"] == 20


def test_a_forgotten_jobs_key_is_answered_from_the_database(tmp_path: Path) -> None:
    with JobStore(tmp_path / "s.sqlite3") as store:
        store.save(_stored_jobs(MAX_FINAL_JOBS + 1))
        service = OrchestratorService(SHOW, session=_NoSession(), store=store)  # type: ignore[arg-type]
        assert "j0" not in service.book.jobs
        request = SubmitRequest(text="永", client_id="kiosk-1", idempotency_key="k-0")
        reply = asyncio.run(service.on_submit(request))
        assert service.fatal is None
        assert reply.ok and reply.job_id == "j0" and reply.state == "done"
        assert store.load().job_counts == {"done": MAX_FINAL_JOBS + 1, "queued": 1}


def test_planned_durations_are_kept_for_the_latest_texts_only(tmp_path: Path) -> None:
    with JobStore(tmp_path / "s.sqlite3") as store:
        service = OrchestratorService(SHOW, session=_NoSession(), store=store)  # type: ignore[arg-type]
        for k in range(CACHED_DURATIONS + 10):
            service.estimates.remember(f"text:{k}", KindPlans({"quadrotor-brush": 10.0 + k}))
        assert len(service.estimates.cached) == CACHED_DURATIONS
        assert "text:9" not in service.estimates.cached and "text:10" in service.estimates.cached


class _NoSession:
    """Stands for a Zenoh session the test never publishes on (the reply needs none)."""

    def __getattr__(self, name: str) -> Any:
        raise AttributeError(name)


def test_finished_jobs_count_every_change_and_hold_the_latest_to_finish() -> None:
    queued = _stored_jobs(1)[1]  # one queued job
    finished = FinishedJobs([queued], max_jobs=2)
    assert finished.counts == {"queued": 1} and finished.overflow() == []
    jobs = [msgspec.structs.replace(queued, job_id=f"q{k}", seq=k + 2) for k in range(3)]
    assert all(finished.changed(None, job) == [] for job in jobs)
    done = [transition(j, "done", 10.0 - k) for k, j in enumerate(jobs)]  # finish q0, q1, q2
    assert [finished.changed(j, d) for j, d in zip(jobs, done, strict=True)] == [[], [], ["q0"]]
    assert finished.changed(done[1], done[1]) == []  # a finished job saved again: no new entry
    assert finished.counts == {"queued": 1, "done": 3}
