"""A phrase whose character ends unwritten before the phrase began (``orchestrator/phrases.py``,
``ended_unbegun``): written whole or not at all, its other characters end with it, the operator
is alerted once, and the visitor's ticket says so (``kiosk/phrase_view.py``)."""

from __future__ import annotations

from test_orchestrator_phrases import _assigned, _book, _online, _phrase, _ready

from bus.messages import AgentReport, ErrorInfo, JobState, OperatorCommand
from kiosk.phrase_view import phrase_view
from orchestrator.jobs import to_state
from orchestrator.phrases import PHRASE_INCOMPLETE

PLACES = {"uav1": 1, "uav2": 2, "uav3": 3, "uav4": 4}


def _cancels(eff: object) -> set[tuple[str, str | None]]:
    return {(v, c.job_id) for v, c in eff.commands if c.command == "cancel"}  # type: ignore[attr-defined]


def test_a_character_no_vehicle_can_fly_before_the_start_ends_its_phrase() -> None:
    book = _book()
    for vid in ("uav1", "uav2", "uav3", "uav4"):
        _online(book, vid, 0.0)
    ids, eff = _phrase(book, "新年快乐", 1.0)
    assert len(_assigned(eff)) == 4
    _ready(book, "uav1", ids[0], 3.0)  # holding at its start, waiting for the others
    error = ErrorInfo(code="bounds", message="快 does not fit the board's area")
    failed = AgentReport(vehicle_id="uav3", job_id=ids[2], event="failed", error=error)
    _, eff = book.report(failed, 4.0)
    states = [book.jobs[j] for j in ids]
    assert [j.state for j in states] == ["failed"] * 4
    assert [j.error.code for j in states if j.error] == ["phrase_incomplete"] * 2 + [
        "bounds",
        "phrase_incomplete",
    ]
    assert states[0].error is not None and "快 of its phrase could not be written" in (
        states[0].error.message
    )
    assert _cancels(eff) == {("uav1", ids[0]), ("uav2", ids[1]), ("uav4", ids[3])}
    (alert,) = [e for e in eff.events if e.kind == "phrase_ended"]
    assert alert.level == "alert" and alert.job_id == ids[0]
    assert alert.message.startswith("phrase 新年快乐: 快 failed before it began (快 does not fit")
    assert alert.message.endswith("the other 3 end with it")
    assert not book.active_jobs()  # every vehicle free for the queue behind


def test_an_operators_cancel_of_one_waiting_character_cancels_the_phrase_with_the_reason() -> None:
    book = _book()
    _online(book, "uav1", 0.0)  # one free board: the phrase waits in the queue
    ids, _ = _phrase(book, "新年", 1.0)
    cancel = OperatorCommand(command="cancel", job_id=ids[1], reason="年 is misspelt")
    reply, eff = book.operator(cancel, 2.0)
    assert reply.ok
    assert [book.jobs[j].state for j in ids] == ["cancelled", "cancelled"]
    assert all(book.jobs[j].error.reason == "年 is misspelt" for j in ids)  # type: ignore[union-attr]
    (told,) = [e for e in eff.events if e.kind == "phrase_ended"]
    assert told.level == "info" and "年 cancelled before it began" in told.message
    # the visitor's one ticket: cancelled, with the operator's words
    states = [to_state(book.jobs[j]) for j in ids]
    view = phrase_view("新年", states, PLACES)
    assert view["state"] == "cancelled" and view["final"] and view["reason"] == "年 is misspelt"


def test_after_the_start_a_cancelled_character_leaves_the_others_writing() -> None:
    book = _book()
    for vid in ("uav1", "uav2"):
        _online(book, vid, 0.0)
    ids, _ = _phrase(book, "新年", 1.0)
    for now in (3.0, 3.5):
        for vid, job_id in zip(["uav1", "uav2"], ids, strict=True):
            _ready(book, vid, job_id, now)
    book.report(AgentReport(vehicle_id="uav1", job_id=ids[0], event="started"), 3.6)
    reply, eff = book.operator(OperatorCommand(command="cancel", job_id=ids[1]), 4.0)
    assert reply.ok and [book.jobs[j].state for j in ids] == ["writing", "cancelled"]
    assert not [e for e in eff.events if e.kind == "phrase_ended"]


def test_the_visitor_sees_which_character_could_not_be_written() -> None:
    book = _book()
    for vid in ("uav1", "uav2"):
        _online(book, vid, 0.0)
    ids, _ = _phrase(book, "新年", 1.0)
    error = ErrorInfo(code="bounds", message="no fit")
    book.report(AgentReport(vehicle_id="uav1", job_id=ids[0], event="failed", error=error), 2.0)
    states: list[JobState | None] = [to_state(book.jobs[j]) for j in ids]
    view = phrase_view("新年", states, PLACES)
    chars = view["phrase"]["characters"]
    assert view["state"] == "failed" and view["final"] and view["phrase"]["written"] == 0
    assert [c["failure"] for c in chars] == ["bounds", PHRASE_INCOMPLETE]
    assert [c["with_phrase"] for c in chars] == [False, True]  # the page: "goes whole or not"
