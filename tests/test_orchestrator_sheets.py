"""Sheets on the boards (``orchestrator/sheets.py``): a board whose character the crew takes
away waits for its fresh sheet, a cloth dries, and the ETAs count both."""

from __future__ import annotations

import pytest

from bus.messages import AgentReport, JobMetrics, OperatorCommand, SubmitRequest, VehicleStatus
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import EtaModel, VehicleInfo
from orchestrator.sheets import BoardSheets
from showfile import ShowError, parse_show

VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)
METRICS = JobMetrics(rmse_pen_down_m=0.01, rmse_m=0.01, max_error_m=0.02, iou=0.9, duration_s=9)


def _book(b1: BoardSheets, *, vehicles: tuple[VehicleInfo, ...] = VEHICLES) -> Book:
    config = CoreConfig(
        show_id="t",
        vehicles=vehicles,
        eta=EtaModel(time_scale=2.0),
        boards=(("b1", b1),),
        sheet_change_s=40.0,
    )
    book = Book(config, now_s=0.0)
    for view in vehicles:
        book.liveliness(view.vehicle_id, True, 0.0)
        _idle(book, view.vehicle_id, 0.0)
    return book


def _idle(book: Book, vid: str, now_s: float) -> Effects:
    return book.status(VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="idle"), now_s)


def _submit(book: Book, job_id: str, now_s: float) -> None:
    reply, _ = book.submit(job_id, SubmitRequest(text="L"), label="L", estimate_s=10.0, now_s=now_s)
    assert reply.ok


def _write(book: Book, vid: str, job_id: str, now_s: float) -> Effects:
    book.report(AgentReport(vehicle_id=vid, job_id=job_id, event="started"), now_s)
    done = AgentReport(vehicle_id=vid, job_id=job_id, event="done", metrics=METRICS)
    return book.report(done, now_s + 1.0)[1]


def _assigned(eff: Effects) -> list[tuple[str, str]]:
    return [(vid, c.job.job_id) for vid, c in eff.commands if c.command == "assign" and c.job]


def test_a_character_taken_away_leaves_its_board_waiting_for_the_crew() -> None:
    book = _book(BoardSheets("per_character"), vehicles=VEHICLES[:1])
    _submit(book, "j1", 1.0)
    eff = _write(book, "uav1", "j1", 2.0)
    assert [e.kind for e in eff.events if e.level == "info"][-1] == "sheet_due"
    _submit(book, "j2", 4.0)
    assert _assigned(_idle(book, "uav1", 5.0)) == []  # uav1 is back, its board is not
    snapshot = book.snapshot(5.0)
    assert snapshot.dirty_boards == ["b1"] and snapshot.alerts == []  # routine, not an alert
    (j2,) = [j for j in snapshot.jobs if j.job_id == "j2"]
    assert j2.eta_s == pytest.approx(3.0 + 40.0 / 2.0 - 5.0 + 11.0 / 2.0)  # crew, then approach
    reply, eff = book.operator(OperatorCommand(command="fresh_sheet", board_id="b1"), 33.0)
    assert reply.ok and _assigned(eff) == [("uav1", "j2")]
    assert book.sheets.turnaround_s == pytest.approx((33.0 - 3.0) * 2.0)  # the crew's own pace


def test_the_etas_count_the_crew_after_each_character() -> None:
    book = _book(BoardSheets("per_character"), vehicles=VEHICLES[:1])
    for i in range(1, 4):
        _submit(book, f"j{i}", 1.0)
    etas = {j.job_id: j.eta_s for j in book.snapshot(1.0).jobs if j.state == "queued"}
    # time scale 2: j1 approaches (11 s) and writes (10 s); b1 then waits 40 s for its sheet
    # (longer than uav1's 9 s back); j2 approaches once it has one
    j2_start = 1.0 + (11.0 + 10.0 + 40.0 + 11.0) / 2.0
    assert etas["j2"] == pytest.approx(j2_start - 1.0)
    assert etas["j3"] == pytest.approx(j2_start + (10.0 + 40.0 + 11.0) / 2.0 - 1.0)


def test_another_board_writes_while_one_waits_for_its_sheet() -> None:
    book = _book(BoardSheets("per_character"))
    _submit(book, "j1", 1.0)
    _write(book, "uav1", "j1", 2.0)
    _submit(book, "j2", 4.0)
    assert book.jobs["j2"].vehicle_id == "uav2"  # b2 changes no sheet
    _submit(book, "j3", 4.0)
    assert _assigned(_idle(book, "uav1", 20.0)) == []


def test_a_drying_cloth_takes_no_job_for_its_drying_time() -> None:
    book = _book(BoardSheets("none", dry_s=30.0), vehicles=VEHICLES[:1])
    _submit(book, "j1", 1.0)
    eff = _write(book, "uav1", "j1", 2.0)
    assert "sheet_due" not in [e.kind for e in eff.events]
    _submit(book, "j2", 4.0)
    assert _assigned(_idle(book, "uav1", 17.0)) == []  # wet until 3 + 30 / 2 = 18 s
    assert _assigned(book.tick(18.1)) == [("uav1", "j2")]
    assert book.snapshot(18.1).dirty_boards == []


def test_a_board_waiting_for_its_sheet_still_waits_after_a_restart() -> None:
    book = _book(BoardSheets("per_character"), vehicles=VEHICLES[:1])
    _submit(book, "j1", 1.0)
    _write(book, "uav1", "j1", 2.0)
    _submit(book, "j2", 4.0)
    restarted = Book(
        book.config, list(book.jobs.values()), now_s=10.0, sheet_boards=book.sheets.waiting
    )
    restarted.liveliness("uav1", True, 10.0)
    assert _assigned(_idle(restarted, "uav1", 10.0)) == []
    reply, eff = restarted.operator(OperatorCommand(command="fresh_sheet", board_id="b1"), 12.0)
    assert reply.ok and _assigned(eff) == [("uav1", "j2")]


def test_when_spoiled_boards_are_written_over() -> None:
    book = _book(BoardSheets("when_spoiled"), vehicles=VEHICLES[:1])
    _submit(book, "j1", 1.0)
    _write(book, "uav1", "j1", 2.0)
    _submit(book, "j2", 4.0)  # given at once: the next character goes over the last
    assert (book.jobs["j2"].vehicle_id, book.jobs["j2"].state) == ("uav1", "assigned")
    refused = book.operator(OperatorCommand(command="fresh_sheet", board_id="b1"), 6.0)[0]
    assert refused.error is not None and refused.error.code == "bad_state"


SHOW = """
show_id: sheets
boards:
  - {id: b1, center_m_enu: [0, 0, 0.75], size_m: [1, 1], writing_area_m: [0.6, 0.6],
     sheets: per_character, dry_s: 20}
vehicles:
  - {id: uav1, backend: sim, board: b1, home_m_enu: [0, -1, 0]}
"""


def test_a_drying_time_on_a_board_whose_sheet_is_changed_is_an_error_naming_it() -> None:
    with pytest.raises(ShowError) as raised:
        parse_show(SHOW)
    assert "boards" in str(raised.value) and "dry_s goes with sheets: none" in str(raised.value)
