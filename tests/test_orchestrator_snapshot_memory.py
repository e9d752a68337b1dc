"""What a reconnecting console missed: the snapshot's recent events come from the database and it
carries the open alerts, each until its cause is gone; both survive an orchestrator restart."""

from __future__ import annotations

import io
from collections.abc import Iterator
from contextlib import redirect_stdout
from pathlib import Path

import pytest
from test_orchestrator_service import RunningOrchestrator, eventually, make_show

from bus.keys import ShowKeys
from bus.messages import (
    MAX_SNAPSHOT_ALERTS,
    AgentReport,
    CommandReply,
    Event,
    OperatorCommand,
    ShowSnapshot,
    SubmitReply,
    SubmitRequest,
    VehicleStatus,
)
from bus.rpc import query, query_one
from bus.session import BusSettings, Session, free_tcp_endpoint, open_session
from cli.main import main as skyquill
from orchestrator.core import Book, CoreConfig
from orchestrator.core_types import Effects
from orchestrator.fleet import VehicleInfo
from orchestrator.store import JobStore

VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)


def _book(**kw: object) -> Book:
    book = Book(CoreConfig(show_id="t", vehicles=VEHICLES), now_s=0.0, **kw)  # type: ignore[arg-type]
    for vid in ("uav1", "uav2"):
        _status(book, vid, "idle", 0.0)
    return book


def _status(book: Book, vid: str, state: str, now_s: float, job_id: str | None = None) -> None:
    book.liveliness(vid, True, now_s)
    status = VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state=state, job_id=job_id)  # type: ignore[arg-type]
    book.status(status, now_s)


def _op(book: Book, now_s: float, command: str, **kw: object) -> None:
    reply, _ = book.operator(OperatorCommand(command=command, **kw), now_s)  # type: ignore[arg-type]
    assert reply.ok, reply


def _open(book: Book) -> list[tuple[str, str | None]]:
    return [(e.kind, e.vehicle_id) for e in book.snapshot(1e3).alerts]


def test_a_held_vehicle_alerts_until_it_is_released_and_an_estop_of_all_until_all_are() -> None:
    book = _book()
    _status(book, "uav1", "fault", 1.0)  # held by the orchestrator: an alert that lasts
    assert _open(book) == [("vehicle_held", "uav1")]
    _op(book, 2.0, "estop")
    assert _open(book) == [("vehicle_held", "uav1"), ("operator", None)]
    assert book.snapshot(3.0, include_final=False).alerts == book.snapshot(3.0).alerts  # fleet
    _op(book, 4.0, "release", vehicle_id="uav1")
    assert _open(book) == [("operator", None)]  # uav2 is still held by the estop
    _op(book, 5.0, "release", vehicle_id="uav2")
    assert _open(book) == []


def test_lost_fault_and_half_written_board_alerts_close_with_their_cause() -> None:
    book = _book()
    book.liveliness("uav2", False, 1.0)
    book.tick(3.0)
    assert _open(book) == [("vehicle_lost", "uav2")]
    _status(book, "uav2", "idle", 4.0)
    assert _open(book) == []
    fault = Event(time_s=5.0, level="alert", kind="vehicle_fault", message="uav1 fault: motor 3")
    book.vehicle_event("uav1", fault, 5.0)
    assert _open(book) == [("vehicle_fault", "uav1")]  # its status may not say so yet
    _status(book, "uav1", "idle", 5.0)
    assert _open(book) == [("vehicle_fault", "uav1")]  # not a status sent after the fault
    _status(book, "uav1", "idle", 6.0)
    assert _open(book) == []
    said = book.telemetry("uav1", 1.0, None, 7.0, writing=True).events
    assert [e.kind for e in said] == ["limit"]  # an alert of a moment: in the log only
    assert _open(book) == []
    reply, _ = book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=20.0, now_s=8.0)
    job = book.jobs["j1"]
    assert reply.ok and job.vehicle_id is not None
    report = AgentReport(
        vehicle_id=job.vehicle_id, job_id="j1", event="started", planned_duration_s=20.0
    )
    assert book.report(report, 9.0)[0].ok
    _op(book, 10.0, "land", vehicle_id=job.vehicle_id)
    assert _open(book) == []  # its writing may have ended: the job waits for its word
    _status(book, job.vehicle_id, "landing", 10.5)  # without it: half-written, board dirty
    assert ("board_dirty", job.vehicle_id) in _open(book)
    _op(book, 11.0, "fresh_sheet", board_id=job.board_id)
    assert ("board_dirty", job.vehicle_id) not in _open(book)


def test_a_full_disk_alerts_until_room_is_made_and_a_restart_checks_again() -> None:
    book = _book()
    eff = Effects()
    book.event(eff, 1.0, "alert", "disk_full", "the show's disk is full")
    assert eff.settings_changed and _open(book) == [("disk_full", None)]
    book.tick(50.0)
    assert _open(book) == [("disk_full", None)]  # it lasts: nothing else closes it
    restarted = Book(book.config, now_s=60.0, open_alerts=book.open_alerts())
    assert _open(restarted) == []  # the new orchestrator's own disk check says it again
    eff = Effects()
    book.event(eff, 70.0, "info", "disk_room", "room again")
    assert eff.settings_changed and _open(book) == []


def test_the_snapshot_carries_the_newest_open_alerts_only() -> None:
    vehicles = tuple(VehicleInfo(f"v{i}", "quadrotor-brush", f"b{i}") for i in range(80))
    book = Book(CoreConfig(show_id="t", vehicles=vehicles), now_s=0.0)
    for i, info in enumerate(vehicles):
        _status(book, info.vehicle_id, "fault", float(i))
    alerts = book.snapshot(100.0).alerts
    assert len(book.open_alerts()) == 80 and len(alerts) == MAX_SNAPSHOT_ALERTS
    assert [e.vehicle_id for e in alerts] == [f"v{i}" for i in range(30, 80)]


def test_open_alerts_are_stored_with_the_settings_and_restored(tmp_path: Path) -> None:
    book = _book()
    _, eff = book.operator(OperatorCommand(command="estop", vehicle_id="uav2"), 1.0)
    assert eff.settings_changed
    with JobStore(tmp_path / "show.sqlite3") as store:
        store.save(eff.jobs.values(), eff.events, open_alerts=book.open_alerts())
        stored = store.load()
    assert [e.message for e in stored.open_alerts] == ["operator: estop uav2"]
    restarted = Book(book.config, now_s=2.0, held_vehicles=["uav2"], open_alerts=stored.open_alerts)
    assert _open(restarted) == [("operator", "uav2")]


@pytest.fixture(scope="module")
def endpoint() -> Iterator[str]:
    ep = free_tcp_endpoint()
    with open_session(BusSettings(router_listen=[ep], connect=[ep]), role="router"):
        yield ep


def test_a_restarted_orchestrator_serves_earlier_events_and_open_alerts(
    tmp_path: Path, endpoint: str
) -> None:
    path, show = make_show(tmp_path, "memory", endpoint)
    keys = ShowKeys(show.show_id)
    settings = BusSettings(router_listen=[], connect=[endpoint])

    def snapshot(client: Session) -> ShowSnapshot | None:
        replies = query(client, keys.snapshot, None, ShowSnapshot, timeout_s=0.5)
        return replies[0].value if replies else None

    with open_session(settings, role="client") as client:
        with RunningOrchestrator(show):
            eventually(lambda: snapshot(client))
            reply = query_one(client, keys.submit, SubmitRequest(text="L"), SubmitReply)
            estop = OperatorCommand(command="estop", vehicle_id="uav3", operator="ana")
            assert query_one(client, keys.command, estop, CommandReply).ok
            before = eventually(lambda: snapshot(client))
            assert [e.kind for e in before.alerts] == ["operator"]
        with RunningOrchestrator(show):
            after = eventually(lambda: snapshot(client))
            messages = [e.message for e in after.events]
            assert messages[: len(before.events)] == [e.message for e in before.events]
            assert any(e.job_id == reply.job_id for e in after.events)  # job_submitted
            assert "operator (ana): estop uav3" in messages  # the key's identity, then the name
            assert [(e.kind, e.vehicle_id, e.message) for e in after.alerts] == [
                ("operator", "uav3", "operator (ana): estop uav3")
            ]
            out = io.StringIO()
            with redirect_stdout(out):
                assert skyquill(["status", str(path)]) == 0
            assert "operator: operator (ana): estop uav3" in out.getvalue().splitlines()[-1]
            release = OperatorCommand(command="release", vehicle_id="uav3")
            assert query_one(client, keys.command, release, CommandReply).ok
            assert eventually(lambda: snapshot(client)).alerts == []
