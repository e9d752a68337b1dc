"""A phrase is moderated as one submission (``orchestrator/operator.py``): approving or
rejecting any one of its characters approves or rejects them all, the reason on each, so a
phrase is never dispatched in part."""

from __future__ import annotations

from bus.messages import OperatorCommand, SubmitRequest, VehicleStatus
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo

VEHICLES = tuple(VehicleInfo(f"uav{i}", "quadrotor-brush", f"b{i}") for i in range(1, 5))


def _book() -> tuple[Book, list[str]]:
    """Four vehicles online on a moderated show, a phrase and a lone job awaiting approval."""
    book = Book(CoreConfig(show_id="t", vehicles=VEHICLES, moderation=True), now_s=0.0)
    for v in VEHICLES:
        book.liveliness(v.vehicle_id, True, 0.0)
        book.status(VehicleStatus(vehicle_id=v.vehicle_id, kind=v.kind, state="idle"), 0.0)
    ids = [f"p{i}" for i in range(4)]
    request = SubmitRequest(text="新年快乐", phrase=True)
    reply, _ = book.submit_phrase(ids, request, [10.0] * 4, now_s=1.0)
    assert reply.ok and reply.job_id == "p0"
    book.submit("lone", SubmitRequest(text="永"), label="永", estimate_s=5.0, now_s=1.5)
    assert {j.state for j in book.jobs.values()} == {"awaiting_approval"}
    return book, ids


def _assigned(eff: Effects) -> dict[str, str]:
    return {c.job.job_id: vid for vid, c in eff.commands if c.command == "assign" and c.job}


def test_approving_one_character_approves_the_whole_phrase_and_it_goes_together() -> None:
    book, ids = _book()
    reply, eff = book.operator(OperatorCommand(command="approve", job_id="p2"), 2.0)
    assert reply.ok and reply.message == "phrase 新年快乐 (4 characters, p0) approved"
    assert _assigned(eff) == dict(zip(ids, ["uav1", "uav2", "uav3", "uav4"], strict=True))
    assert book.jobs["lone"].state == "awaiting_approval"  # nothing else is decided
    [line] = [e.message for e in eff.events if e.kind == "operator"]
    assert line == "operator: approve p2 (phrase p0, 4 characters)"


def test_rejecting_one_character_rejects_every_one_with_the_reason() -> None:
    book, ids = _book()
    why = "不适合展出"
    command = OperatorCommand(command="reject", job_id="p3", reason=why)
    reply, eff = book.operator(command, 2.0)
    assert reply.ok and reply.message == "phrase 新年快乐 (4 characters, p0) rejected"
    for job_id in ids:
        job = book.jobs[job_id]
        assert job.state == "rejected" and job.error is not None
        assert (job.error.code, job.error.reason) == ("rejected", why), job_id
    assert set(eff.jobs) == set(ids)  # each character is published rejected
    assert book.jobs["lone"].state == "awaiting_approval"
    again = book.operator(OperatorCommand(command="approve", job_id="p0"), 3.0)[0]
    assert not again.ok and again.error is not None and again.error.code == "bad_state"


def test_a_bulk_rejection_naming_one_character_takes_its_phrase() -> None:
    book, ids = _book()
    command = OperatorCommand(command="reject", job_ids=["p1"], reason="spam")
    reply, _ = book.operator(command, 2.0)
    assert reply.ok and sorted(reply.job_ids or []) == ids
    assert all(book.jobs[j].state == "rejected" for j in ids)
    assert book.jobs["lone"].state == "awaiting_approval"


def test_a_lone_job_is_moderated_alone() -> None:
    book, ids = _book()
    reply, _ = book.operator(OperatorCommand(command="approve", job_id="lone"), 2.0)
    assert reply.ok and reply.message == "lone approved"
    assert all(book.jobs[j].state == "awaiting_approval" for j in ids)
