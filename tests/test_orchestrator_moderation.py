"""Bulk moderation (pure): one operator command rejects or cancels many waiting jobs, and never
touches a job a vehicle has."""

from __future__ import annotations

import msgspec
import pytest

from bus.codec import MessageError, decode
from bus.messages import (
    MAX_BULK_JOBS,
    AgentReport,
    OperatorCommand,
    OperatorReply,
    SubmitRequest,
    VehicleStatus,
)
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo
from orchestrator.jobs import Job

VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)


def _book(*, moderation: bool, vehicles: tuple[VehicleInfo, ...] = VEHICLES) -> Book:
    return Book(CoreConfig(show_id="t", vehicles=vehicles, moderation=moderation), now_s=0.0)


def _submit(book: Book, job_id: str, client_id: str, now_s: float = 1.0) -> None:
    request = SubmitRequest(text="L", client_id=client_id)
    reply, _ = book.submit(job_id, request, label="L", estimate_s=20.0, now_s=now_s)
    assert reply.ok, reply


def _bulk(book: Book, now_s: float, **fields: object) -> tuple[OperatorReply, Effects]:
    reply, eff = book.operator(OperatorCommand(**fields), now_s)  # type: ignore[arg-type]
    assert isinstance(reply, OperatorReply), reply
    return reply, eff


def _present(book: Book, vid: str, now_s: float, **status: object) -> None:
    book.liveliness(vid, True, now_s)
    book.status(VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", **status), now_s)  # type: ignore[arg-type]


def _waiting(job_id: str, seq: int, client_id: str) -> Job:
    """A job awaiting approval, as a restarted orchestrator finds it (past any submission cap)."""
    return Job(
        job_id=job_id,
        seq=seq,
        state="awaiting_approval",
        kind="text",
        text="L",
        label="L",
        client_id=client_id,
        created_at_s=1.0,
        updated_at_s=1.0,
    )


def test_one_command_rejects_a_flood_of_200_and_leaves_the_other_client_alone() -> None:
    flood = [f"f{i:03d}" for i in range(200)]
    jobs = [_waiting(job_id, seq, "flood") for seq, job_id in enumerate(flood, start=1)]
    jobs += [
        _waiting(job_id, 300 + seq, "kiosk-7") for seq, job_id in enumerate(("k1", "k2", "k3"))
    ]
    config = CoreConfig(show_id="t", vehicles=VEHICLES, moderation=True)
    book = Book(config, jobs, now_s=2.0)
    reply, eff = _bulk(
        book, 5.0, command="reject", client_id="flood", reason="junk", operator="ana"
    )
    assert reply.ok and reply.job_ids == flood and reply.skipped == []
    assert reply.message == "rejected 200 job(s) of client 'flood'"
    assert all(book.jobs[j].state == "rejected" for j in flood)
    assert {book.jobs[j].error.message for j in flood} == {"junk"}  # type: ignore[union-attr]
    assert [book.jobs[j].state for j in ("k1", "k2", "k3")] == ["awaiting_approval"] * 3
    # each one as the one-job reject does it: stored and published, and its own log line
    assert sorted(eff.jobs) == flood and not eff.progressed
    lines = {e.job_id: e.message for e in eff.events if e.kind == "operator"}
    assert lines == {j: f"ana: reject {j} (junk)" for j in flood}
    assert book.waiting_count() == 3
    again, eff = _bulk(book, 6.0, command="reject", client_id="flood")
    assert again.ok and again.job_ids == [] and not eff.jobs  # nothing left to do


def test_a_certificate_that_declares_a_new_client_id_each_time_is_rejected_by_its_name() -> None:
    book = _book(moderation=True)
    for i in range(6):  # one certificate, six made-up client ids
        request = SubmitRequest(text="L", client_id=f"visitor-{i}")
        reply, _ = book.submit(
            f"f{i}", request, label="L", estimate_s=20.0, now_s=1.0, submitted_by="submitter@x"
        )
        assert reply.ok
    _submit(book, "k1", "visitor-0")  # a visitor of the kiosk who happens to share an id
    reply, _ = _bulk(book, 2.0, command="reject", client_id="submitter@x")
    assert reply.ok and reply.job_ids == [f"f{i}" for i in range(6)]
    assert book.jobs["k1"].state == "awaiting_approval"


def test_bulk_cancel_takes_waiting_jobs_and_never_one_a_vehicle_has() -> None:
    book = _book(moderation=False)
    _present(book, "uav1", 0.0, state="idle")
    _present(book, "uav2", 0.0, state="idle")
    for i in range(5):
        _submit(book, f"j{i}", "flood")
    held = {vid: book.active_job_of(vid) for vid in ("uav1", "uav2")}
    assert {j.job_id for j in held.values() if j} == {"j0", "j1"}
    report = AgentReport(vehicle_id="uav1", job_id="j0", event="started", planned_duration_s=20.0)
    assert book.report(report, 2.0)[0].ok  # j0 is being written, j1 assigned
    reply, eff = _bulk(book, 3.0, command="cancel", client_id="flood")
    assert reply.ok and reply.job_ids == ["j2", "j3", "j4"]
    assert [(s.job_id, s.state) for s in reply.skipped] == [("j0", "writing"), ("j1", "assigned")]
    assert "j0 (writing on uav1" in reply.message and "2 skipped" in reply.message
    assert not eff.commands  # no vehicle is told to stop
    assert book.jobs["j0"].state == "writing" and book.jobs["j1"].state == "assigned"


def test_a_queued_job_waiting_for_its_lost_writer_is_left_to_it() -> None:
    book = _book(moderation=False, vehicles=VEHICLES[:1])
    _present(book, "uav1", 0.0, state="idle")
    _submit(book, "j1", "flood")
    report = AgentReport(vehicle_id="uav1", job_id="j1", event="started", planned_duration_s=20.0)
    assert book.report(report, 2.0)[0].ok
    book.liveliness("uav1", False, 3.0)
    book.tick(5.0)  # lost: j1 is queued again, for uav1 alone (it may be writing on)
    assert book.jobs["j1"].state == "queued"
    reply, _ = _bulk(book, 6.0, command="cancel", job_ids=["j1"])
    assert reply.job_ids == [] and "may be writing it" in reply.skipped[0].reason
    assert book.jobs["j1"].state == "queued"


def test_a_selection_names_what_it_did_and_what_it_left() -> None:
    book = _book(moderation=True)
    for job_id in ("a1", "a2", "a3"):
        _submit(book, job_id, "someone")
    assert book.operator(OperatorCommand(command="approve", job_id="a2"), 2.0)[0].ok
    selection = ["a3", "nope", "a1", "a2", "a1"]
    reply, _ = _bulk(book, 3.0, command="reject", job_ids=selection)
    assert reply.job_ids == ["a1", "a3"]  # submission order, each once
    skipped = [(s.job_id, s.state, s.reason) for s in reply.skipped]
    assert skipped == [
        ("a2", "queued", "queued (approved already: cancel it)"),
        ("nope", None, "no such job"),
    ]
    reply, _ = _bulk(book, 4.0, command="cancel", job_ids=["a1", "a2"])
    assert reply.job_ids == ["a2"] and reply.skipped[0].reason == "already rejected"


@pytest.mark.parametrize(
    ("fields", "code"),
    [
        ({"command": "reject", "client_id": "x", "job_id": "a1"}, "invalid"),
        ({"command": "cancel", "client_id": "x", "job_ids": ["a1"]}, "invalid"),
        ({"command": "approve", "job_ids": ["a1"]}, "invalid"),
        ({"command": "reject", "client_id": "nobody"}, "unknown_client"),
    ],
)
def test_a_bulk_command_that_names_its_jobs_badly_changes_nothing(
    fields: dict[str, object], code: str
) -> None:
    book = _book(moderation=True)
    _submit(book, "a1", "someone")
    reply, eff = book.operator(OperatorCommand(**fields), 2.0)  # type: ignore[arg-type]
    assert not reply.ok and reply.error is not None and reply.error.code == code
    assert book.jobs["a1"].state == "awaiting_approval" and not eff.jobs and not eff.events


def test_a_selection_is_bounded_and_not_empty_on_the_wire() -> None:
    for ids in ([], [f"j{i}" for i in range(MAX_BULK_JOBS + 1)]):
        raw = msgspec.json.encode({"command": "reject", "job_ids": ids})
        with pytest.raises(MessageError) as err:
            decode(raw, OperatorCommand)
        assert err.value.info.code == "invalid" and err.value.info.field == "$.job_ids"
