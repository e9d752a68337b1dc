"""Operator holds (pure): a landed or stopped vehicle flies again only when released by name."""

from __future__ import annotations

from bus.messages import AgentReport, ErrorInfo, OperatorCommand, SubmitRequest, VehicleStatus
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo, ready_for_job

VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)


def _book() -> Book:
    book = Book(CoreConfig(show_id="t", vehicles=VEHICLES), now_s=0.0)
    for vid in ("uav1", "uav2"):
        book.liveliness(vid, True, 0.0)
        book.status(VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="idle"), 0.0)
    return book


def _submit(book: Book, job_id: str, now_s: float) -> Effects:
    reply, eff = book.submit(
        job_id, SubmitRequest(text="L"), label="L", estimate_s=20.0, now_s=now_s
    )
    assert reply.ok, reply
    return eff


def _assigned(eff: Effects) -> list[tuple[str, str]]:
    return [(vid, c.job.job_id) for vid, c in eff.commands if c.command == "assign" and c.job]


def _idle(book: Book, vid: str, now_s: float) -> Effects:
    status = VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="idle")
    return book.status(status, now_s)


def _op(book: Book, now_s: float, command: str, **kw: object) -> tuple[bool, str, Effects]:
    reply, eff = book.operator(OperatorCommand(command=command, **kw), now_s)  # type: ignore[arg-type]
    return reply.ok, reply.message, eff


def test_land_holds_the_vehicle_through_pause_and_resume_of_the_queue() -> None:
    book = _book()
    ok, _, _ = _op(book, 1.0, "land", vehicle_id="uav1")
    assert ok and book.vehicles["uav1"].held
    _op(book, 2.0, "pause")
    ok, message, eff = _op(book, 3.0, "resume")  # the console's `p` `p`
    assert ok and "uav1 held" in message
    _submit(book, "j1", 4.0)
    _submit(book, "j2", 4.0)
    eff = _idle(book, "uav1", 5.0)
    assert _assigned(eff) == []  # uav1 stays down; uav2 took j1 when it was submitted
    assert book.jobs["j2"].state == "queued"
    assert not ready_for_job(book.vehicles["uav1"], 5.0)
    assert book.vehicles["uav1"].summary(None).held


def test_resume_of_the_held_vehicle_itself_does_not_release_it() -> None:
    book = _book()
    _op(book, 1.0, "land", vehicle_id="uav1")
    ok, message, _ = _op(book, 2.0, "resume", vehicle_id="uav1")
    assert ok and "release" in message
    assert book.vehicles["uav1"].held and book.vehicles["uav1"].paused


def test_release_is_explicit_and_per_vehicle() -> None:
    book = _book()
    _op(book, 1.0, "land_all")
    assert all(v.held for v in book.vehicles.values()) and book.queue_paused
    ok, message, _ = _op(book, 2.0, "release")
    assert not ok and "vehicle_id" in message
    _op(book, 2.5, "resume")
    _submit(book, "j1", 3.0)
    assert book.jobs["j1"].state == "queued"
    ok, message, eff = _op(book, 4.0, "release", vehicle_id="uav2")
    assert ok and message == "uav2 released"
    assert _assigned(eff) == [("uav2", "j1")]
    assert book.vehicles["uav1"].held
    ok, message, _ = _op(book, 5.0, "release", vehicle_id="uav2")
    assert not ok and "not held" in message


def test_estop_holds_and_etas_count_only_vehicles_that_can_fly() -> None:
    book = _book()
    _op(book, 1.0, "estop")
    _op(book, 2.0, "resume")
    assert all(v.held for v in book.vehicles.values()) and not book.queue_paused
    _submit(book, "j1", 3.0)
    assert book.etas(3.0)["j1"] == (1, None)  # nobody can fly: no promise of a time
    ok, _, _ = _op(book, 4.0, "release", vehicle_id="uav9")
    assert not ok
    ok, _, eff = _op(book, 4.0, "release", vehicle_id="uav1")
    assert ok and _assigned(eff) == [("uav1", "j1")]


def test_the_snapshot_reply_carries_the_events_it_is_given_and_fleet_publications_none() -> None:
    book = _book()
    _, land = book.operator(OperatorCommand(command="land", vehicle_id="uav1"), 1.0)
    _, release = book.operator(OperatorCommand(command="release", vehicle_id="uav1"), 2.0)
    logged = [*land.events, *release.events]  # what the service stores and reads back
    events = book.snapshot(3.0, events=logged).events
    assert [e.message for e in events if e.kind == "operator"] == [
        "operator: land uav1",
        "operator: release uav1",
    ]
    assert book.snapshot(3.0, include_final=False).events == []


def _writing(book: Book, vid: str, job_id: str, now_s: float) -> None:
    report = AgentReport(vehicle_id=vid, job_id=job_id, event="started", planned_duration_s=20.0)
    assert book.report(report, now_s)[0].ok
    status = VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="writing", job_id=job_id)
    book.status(status, now_s)


def test_a_board_half_written_by_a_lost_vehicle_waits_for_a_fresh_sheet() -> None:
    book = Book(CoreConfig(show_id="t", vehicles=VEHICLES[:1]), now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    _idle(book, "uav1", 0.0)
    assert _assigned(_submit(book, "j1", 1.0)) == [("uav1", "j1")]
    _writing(book, "uav1", "j1", 2.0)
    assert book.jobs["j1"].state == "writing"
    book.liveliness("uav1", False, 3.0)
    book.tick(4.6)  # past the grace period: lost, j1 requeued for it (it may be writing on)
    assert book.jobs["j1"].state == "queued" and book.dirty_boards == set()
    book.liveliness("uav1", True, 31.0)
    assert _assigned(_idle(book, "uav1", 31.0)) == []  # back without it: the sheet is spoilt
    assert book.jobs["j1"].state == "queued" and book.dirty_boards == {"b1"}
    assert book.snapshot(31.0).dirty_boards == ["b1"]
    alerts = book.snapshot(31.0).alerts
    assert any(e.kind == "board_dirty" for e in alerts)
    held = [e.message for e in alerts if e.kind == "vehicle_held"]
    assert held == ["uav1 held: lost while writing, back without a job; check it, then release it"]
    ok, message, _ = _op(book, 32.0, "fresh_sheet")
    assert not ok and "board_id" in message
    ok, message, _ = _op(book, 32.0, "fresh_sheet", board_id="b9")
    assert not ok and "b1" in message  # the valid boards are listed
    ok, message, eff = _op(book, 33.0, "fresh_sheet", board_id="b1")
    assert ok and _assigned(eff) == [] and not book.dirty_boards  # held still
    ok, message, eff = _op(book, 33.5, "release", vehicle_id="uav1")
    assert ok and _assigned(eff) == [("uav1", "j1")]
    ok, message, _ = _op(book, 34.0, "fresh_sheet", board_id="b1")
    assert not ok and "not waiting" in message


def test_a_job_requeued_before_writing_started_leaves_the_board_clean() -> None:
    book = Book(CoreConfig(show_id="t", vehicles=VEHICLES[:1]), now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    _idle(book, "uav1", 0.0)
    _submit(book, "j1", 1.0)
    assert book.jobs["j1"].state == "assigned"
    _op(book, 2.0, "land", vehicle_id="uav1")
    assert book.jobs["j1"].state == "queued" and not book.dirty_boards


def test_release_all_frees_every_held_vehicle_and_leaves_the_queue_paused() -> None:
    book = _book()
    ok, message, _ = _op(book, 1.0, "release_all")
    assert not ok and "no vehicle is held" in message
    ok, _, _ = _op(book, 2.0, "estop")  # every vehicle: held, the queue paused
    assert ok and all(v.held for v in book.vehicles.values()) and book.queue_paused
    ok, message, eff = _op(book, 3.0, "release_all")
    assert ok and message.startswith("released uav1, uav2") and "resume" in message
    assert not any(v.held or v.paused for v in book.vehicles.values()) and book.queue_paused
    assert eff.settings_changed  # stored: a restarted orchestrator holds nobody


def test_a_job_handed_back_unsettled_after_its_ready_report_leaves_the_board_clean() -> None:
    """The vehicle asked to write (its *ready* report stored) but never settled at the start:
    its hand-back says the brush never touched, so no fresh sheet is wanted."""
    book = Book(CoreConfig(show_id="t", vehicles=VEHICLES[:1]), now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    _idle(book, "uav1", 0.0)
    assert _assigned(_submit(book, "j1", 1.0)) == [("uav1", "j1")]
    ready = AgentReport(vehicle_id="uav1", job_id="j1", event="holding", planned_duration_s=20.0)
    assert book.report(ready, 2.0)[0].ok
    assert book.jobs["j1"].writing_since_s is not None
    error = ErrorInfo(code="not_settled", message="not settled after 2 approaches")
    unsettled = AgentReport(
        vehicle_id="uav1", job_id="j1", event="failed", error=error, retry_after_s=5.0
    )
    assert book.report(unsettled, 3.0)[0].ok
    assert book.jobs["j1"].state == "queued" and not book.dirty_boards
