"""A lost vehicle's job waits for it (``orchestrator/holders.py``): scenarios and a property over
random outages (who comes back, when, with the job written or not)."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from bus.messages import (
    AgentReport,
    ErrorInfo,
    JobMetrics,
    OperatorCommand,
    SubmitRequest,
    VehicleStateName,
    VehicleStatus,
)
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo

VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)
METRICS = JobMetrics(rmse_pen_down_m=0.01, rmse_m=0.01, max_error_m=0.02, iou=0.9, duration_s=9)


def _config(**kw: object) -> CoreConfig:
    return CoreConfig(show_id="t", vehicles=VEHICLES, **kw)  # type: ignore[arg-type]


def _submit(book: Book, job_id: str, now: float) -> None:
    reply, _ = book.submit(job_id, SubmitRequest(text="L"), label="L", estimate_s=20.0, now_s=now)
    assert reply.ok, reply


def _say(book: Book, vid: str, now: float, job_id: str | None = None) -> Effects:
    state: VehicleStateName = "writing" if job_id else "idle"
    return book.status(
        VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state=state, job_id=job_id), now
    )


def _online(book: Book, vid: str, now: float) -> Effects:
    eff = book.liveliness(vid, True, now)
    more = _say(book, vid, now)
    eff.commands += more.commands
    eff.events += more.events
    return eff


def _assigned(eff: Effects) -> list[tuple[str, str]]:
    return [(vid, c.job.job_id) for vid, c in eff.commands if c.command == "assign" and c.job]


def _writing_then_lost(book: Book) -> None:
    """uav1 writes j1 and is lost (a router restart: its token gone for 1.5 s); uav2 is idle."""
    _online(book, "uav1", 0.0)
    _online(book, "uav2", 0.0)
    _submit(book, "j1", 0.5)
    assert book.jobs["j1"].vehicle_id == "uav1"
    book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="started"), 1.0)
    book.liveliness("uav1", False, 2.0)
    book.liveliness("uav2", False, 2.0)
    book.liveliness("uav2", True, 3.6)
    book.tick(3.6)
    assert book.jobs["j1"].state == "queued"
    eff = book.status(VehicleStatus(vehicle_id="uav2", kind="quadrotor-brush", state="idle"), 3.7)
    assert _assigned(eff) == [] and book.jobs["j1"].state == "queued"


def test_a_lost_vehicle_back_with_its_job_has_it_again_not_a_vehicle_back_first() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _writing_then_lost(book)
    book.liveliness("uav1", True, 4.0)
    status = VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="writing", job_id="j1")
    eff = book.status(status, 4.1)
    assert [e.kind for e in eff.events if e.kind == "job_reclaimed"] == ["job_reclaimed"]
    rep = AgentReport(vehicle_id="uav1", job_id="j1", event="done", metrics=METRICS)
    assert book.report(rep, 5.0)[0].ok
    job = book.jobs["j1"]
    assert (job.state, job.vehicle_id, job.attempts) == ("done", "uav1", 1)


def test_a_lost_vehicle_whose_done_report_comes_late_wrote_the_job_once() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _writing_then_lost(book)
    book.tick(8.0)  # uav2 idle all along
    rep = AgentReport(vehicle_id="uav1", job_id="j1", event="done", metrics=METRICS)
    assert book.report(rep, 9.0)[0].ok
    assert (book.jobs["j1"].state, book.jobs["j1"].attempts) == ("done", 1)


def test_a_lost_vehicle_back_without_its_job_frees_it_at_once() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _writing_then_lost(book)
    book.liveliness("uav1", True, 4.0)
    status = VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="returning")
    eff = book.status(status, 4.1)  # it gave the job up (its lease ran out)
    assert "job_released" in [e.kind for e in eff.events]
    assert _assigned(eff) == [("uav2", "j1")]


def test_a_job_its_vehicle_came_back_without_goes_to_it_only_if_no_other_takes_it() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.5)
    book.liveliness("uav1", False, 1.0)
    book.tick(2.5)  # lost: j1 waits for it
    book.liveliness("uav1", True, 3.0)
    eff = book.status(VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle"), 3.0)
    assert "job_released" in [e.kind for e in eff.events] and _assigned(eff) == []
    backoff_s = book.config.refuse_backoff_s
    assert _assigned(book.tick(3.0 + backoff_s)) == [("uav1", "j1")]  # nobody else came


def test_a_job_waiting_for_its_lost_vehicle_still_waits_after_a_restart() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _writing_then_lost(book)
    stored = list(book.jobs.values())
    book = Book(_config(lost_after_s=1.5), stored, now_s=5.0)
    assert _assigned(_online(book, "uav2", 5.0)) == []
    assert book.awaited_by("uav1") is not None
    eff = book.tick(3.6 + book.config.lost_job_hold_s)
    assert _assigned(eff) == []  # uav1 may have written it: only its word or a sheet frees it
    assert [e.kind for e in eff.events] == ["job_waits"]
    assert "fresh sheet on b1" in eff.events[0].message
    snapshot = book.snapshot(20.0)  # the console offers the sheet, and the alert stays open
    assert snapshot.dirty_boards == ["b1"] and [a.kind for a in snapshot.alerts] == ["job_waits"]
    book.operator(OperatorCommand(command="fresh_sheet", board_id="b1"), 20.0)
    assert book.snapshot(20.0).dirty_boards == [] and book.snapshot(20.0).alerts == []


def test_a_fresh_sheet_frees_an_overdue_job_and_its_old_holder_is_refused() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _writing_then_lost(book)
    sheet = OperatorCommand(command="fresh_sheet", board_id="b1")
    early = book.operator(sheet, 5.0)[0]  # uav1 may still be inking: not yet
    assert not early.ok and early.error is not None and early.error.code == "bad_state"
    reply, eff = book.operator(sheet, 3.6 + book.config.lost_job_hold_s)
    assert reply.ok and _assigned(eff) == [("uav2", "j1")]
    rep = AgentReport(vehicle_id="uav1", job_id="j1", event="done", metrics=METRICS)
    late = book.report(rep, 30.0)[0]  # the sheet it was on is gone
    assert late.error is not None and late.error.code == "not_assigned"
    assert (book.jobs["j1"].vehicle_id, book.jobs["j1"].state) == ("uav2", "assigned")


def test_a_holder_back_with_a_written_but_unmeasured_job_fails_it_rather_than_repeat_it() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _writing_then_lost(book)
    book.liveliness("uav1", True, 30.0)
    book.operator(OperatorCommand(command="release", vehicle_id="uav1"), 29.0)
    unmeasured = AgentReport(
        vehicle_id="uav1",
        job_id="j1",
        event="failed",
        progress=1.0,
        error=ErrorInfo(code="unmeasured", message="its agent stopped before measuring it"),
    )
    reply, eff = book.report(unmeasured, 30.0)  # sent by its agent, restarted meanwhile
    assert reply.ok and book.jobs["j1"].state == "failed"
    assert _assigned(eff) == [] and _assigned(_say(book, "uav1", 30.1)) == []


def test_a_holding_report_confirms_the_job_and_changes_nothing() -> None:
    book = Book(_config(), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.5)
    reply, eff = book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="holding"), 1.0)
    assert reply.ok and book.jobs["j1"].state == "assigned" and not eff.jobs
    other = AgentReport(vehicle_id="uav2", job_id="j1", event="holding")
    refused = book.report(other, 1.1)[0].error
    assert refused is not None and refused.code == "not_assigned"


@settings(max_examples=300, deadline=None)
@given(
    whole_bus=st.booleans(),
    back_after_s=st.one_of(st.none(), st.floats(0.1, 19.0)),
    other_back_after_s=st.floats(0.1, 12.0),
    comes_back=st.sampled_from(["done", "writing", "without"]),
    sheet_after_s=st.one_of(st.none(), st.floats(0.1, 19.0)),
)
def test_a_lost_vehicles_job_goes_on_only_when_it_cannot_have_been_written(
    whole_bus: bool,
    back_after_s: float | None,
    other_back_after_s: float,
    comes_back: str,
    sheet_after_s: float | None,
) -> None:
    """uav1 writes j1 when it is cut off (with uav2 too: a router restart; or alone); it comes
    back after ``back_after_s`` (None: never) with j1 written, still writing it, or without it;
    the operator may put a fresh sheet on b1 after ``sheet_after_s``; a present vehicle says its
    status every 0.5 s. uav2 gets j1 only once uav1 said it is without it, or the sheet was
    taken (only after the hold: uav1 may be inking before); uav1 back with j1 written, however
    late, has it done once; never back and no sheet, j1 waits for it, and the operator is told."""
    book = Book(_config(lost_after_s=1.5, lost_job_hold_s=5.0), now_s=0.0)
    _online(book, "uav1", 0.0)
    _online(book, "uav2", 0.0)
    _submit(book, "j1", 0.1)
    book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="started"), 0.2)
    cut_s, hold_end_s = 1.0, 1.0 + 1.5 + 5.0
    book.liveliness("uav1", False, cut_s)
    if whole_bus:
        book.liveliness("uav2", False, cut_s)
    present = {"uav1": False, "uav2": not whole_bus}
    says = {"uav1": None if comes_back == "without" else "j1"}
    released = sheeted = False
    told: list[float] = []
    for step in range(1, 200):
        now = cut_s + 0.1 * step
        effs = [book.tick(now)]
        if not present["uav2"] and now >= cut_s + other_back_after_s:
            present["uav2"] = True
            effs.append(book.liveliness("uav2", True, now))
        if sheet_after_s is not None and not sheeted and now >= cut_s + sheet_after_s:
            job = book.jobs["j1"]
            overdue = book.awaited_by("uav1") == job and now >= hold_end_s - 1e-9
            dirty = "b1" in book.dirty_boards  # uav1 back without it: half-written
            reply, eff = book.operator(OperatorCommand(command="fresh_sheet", board_id="b1"), now)
            assert reply.ok == (overdue or dirty), (now, reply)
            sheeted, sheet_after_s = overdue, None
            effs.append(eff)
        if back_after_s is not None and not present["uav1"] and now >= cut_s + back_after_s:
            present["uav1"], released = True, comes_back == "without" or released
            effs.append(book.liveliness("uav1", True, now))
            effs.append(_say(book, "uav1", now, says["uav1"]))  # heard at once
            if comes_back == "done":
                rep = AgentReport(vehicle_id="uav1", job_id="j1", event="done", metrics=METRICS)
                reply, eff = book.report(rep, now)
                assert reply.ok != sheeted
                effs.append(eff)
                says["uav1"] = None
        if step % 5 == 0:  # heartbeats
            for vid in (v for v, here in present.items() if here):
                active = book.active_job_of(vid)
                job_id = says["uav1"] if vid == "uav1" else active.job_id if active else None
                effs.append(_say(book, vid, now, job_id))
        for eff in effs:
            if ("uav2", "j1") in _assigned(eff):
                assert released or sheeted, (now, back_after_s, comes_back)
            if ("uav1", "j1") in _assigned(eff):
                says["uav1"] = "j1"
            told += [now for e in eff.events if e.kind == "job_waits"]
    job = book.jobs["j1"]
    if sheeted or released:
        assert job.state in ("assigned", "done") and job.attempts == 2, job  # written elsewhere
    elif back_after_s is not None and comes_back == "done":
        assert (job.state, job.vehicle_id, job.attempts) == ("done", "uav1", 1)
    elif back_after_s is not None:
        assert job.state in ("assigned", "writing")  # reclaimed, or back before it was lost
        assert (job.vehicle_id, job.attempts) == ("uav1", 1)
    else:
        assert (job.state, book.awaited_by("uav1")) == ("queued", job)
        assert len(told) == 1 and told[0] >= hold_end_s - 1e-9
