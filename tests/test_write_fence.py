"""The write fence (``bus/fence.py``): no character is written by two vehicles, under any
interleaving of delays, restarts, losses and the operator's stops.

A property over random schedules, a restart of the orchestrator or a loss striking anywhere
from before the vehicle's ready report to the end of its writing: the agent's real lease
(``vehicle_agent/lease.py``) decides tick by tick whether its vehicle may still ink; the
orchestrator's real ``Book`` (restarted from what it stored, or not) decides when another vehicle
may be given the job. The last instant the old holder inks must come before the first instant
anyone else may have it. Both run on one time line here (the agent's monotonic clock and the
orchestrator's Unix clock differ by a constant, and only durations are compared).
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

from hypothesis import given, settings
from hypothesis import strategies as st

from bus.fence import WRITING_SLOWDOWN
from bus.messages import AgentReport, OperatorCommand, SubmitRequest, VehicleStatus
from orchestrator.core import Book, CoreConfig
from orchestrator.fleet import EtaModel, VehicleInfo
from orchestrator.holders import writing_fence_s
from vehicle_agent.lease import JobLease
from vehicle_agent.results import ResultJournal

LOST_AFTER_S = 1.5
TICK_S = 0.01
VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
)


def _config(time_scale: float) -> CoreConfig:
    return CoreConfig(
        show_id="t",
        vehicles=VEHICLES,
        lost_after_s=LOST_AFTER_S,
        eta=EtaModel(time_scale=time_scale),
    )


def _status(vid: str, job_id: str | None, incarnation: str | None = None) -> VehicleStatus:
    state = "writing" if job_id else "idle"
    return VehicleStatus(
        vehicle_id=vid,
        kind="quadrotor-brush",
        state=state,  # type: ignore[arg-type]
        job_id=job_id,
        incarnation=incarnation,
    )


def _last_ink_s(lease: JobLease, begin_s: float, writing_wall_s: float) -> float:
    """When the vehicle stops inking: the end of its writing, or its lease's first breach."""
    t = begin_s
    end = begin_s + writing_wall_s
    while t < end:
        if lease.breach(0.0, t) is not None:
            return t
        t += TICK_S
    return end


def _first_free_s(book: Book, from_s: float, until_s: float) -> float:
    """The first instant from ``from_s`` at which another vehicle may be given j1."""
    book.liveliness("uav2", True, from_s)
    book.status(_status("uav2", None), from_s)
    t = from_s
    while t < until_s:
        book.tick(t)
        job = book.jobs["j1"]
        if job.state != "queued" or job.holder_hold_until_s is None:
            if job.vehicle_id == "uav2" or job.state == "queued":
                return t
        elif t >= job.holder_hold_until_s:
            return t
        t += 0.25
    return math.inf


@settings(max_examples=400, deadline=None)
@given(
    planned_s=st.floats(2.0, 120.0),
    time_scale=st.sampled_from([1.0, 2.0, 4.0, 6.0]),
    slowdown=st.floats(1.0, 3.0),
    delay_to_orch_s=st.floats(0.0, 1.0),
    ack_back=st.booleans(),
    delay_back_s=st.floats(0.0, 1.0),
    settle_s=st.floats(0.0, 2.0),
    outage_after_s=st.floats(0.0, 30.0),
    restart=st.booleans(),
)
def test_the_old_holder_never_inks_once_another_vehicle_may_have_the_job(
    planned_s: float,
    time_scale: float,
    slowdown: float,
    delay_to_orch_s: float,
    ack_back: bool,
    delay_back_s: float,
    settle_s: float,
    outage_after_s: float,
    restart: bool,
) -> None:
    """The vehicle reaches the start of its writing at 10 s and sends its ready report, which
    reaches the orchestrator after ``delay_to_orch_s``; the acknowledgement comes back after
    ``delay_back_s`` (or never); the brush would go down ``settle_s`` after the ready report.
    ``outage_after_s`` after the ready report nothing more is heard either way (the router, the
    orchestrator or the link died, maybe before the report arrived); the orchestrator is
    restarted from its store or goes on, loses the vehicle, and holds the job. The writing takes
    ``slowdown`` times its plan (a loaded host). Then: the old holder inks only before anyone
    else may have the job; and a writer that began keeps writing through the outage to its end
    unless its host is slower than the fence allows for (no board left half-written)."""
    config = _config(time_scale)
    book = Book(config, now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    book.status(_status("uav1", None), 0.0)
    reply, _ = book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=1.0)
    assert reply.ok and book.jobs["j1"].vehicle_id == "uav1"

    lease = JobLease(LOST_AFTER_S, time_scale=time_scale)
    lease.hold("j1", active=True, writing=False, now_s=1.0)
    ready_s = 10.0
    outage_s = ready_s + outage_after_s
    received_s = ready_s + delay_to_orch_s
    ready = AgentReport(
        vehicle_id="uav1", job_id="j1", event="holding", planned_duration_s=planned_s
    )
    if received_s < outage_s:
        book.status(_status("uav1", "j1"), received_s)
        assert book.report(ready, received_s)[0].ok
        if ack_back and received_s + delay_back_s < outage_s:
            lease.acknowledged("j1", ready_s, planned_s)
    begin_s = max(ready_s + settle_s, received_s + delay_back_s)
    writing_wall_s = slowdown * planned_s / time_scale
    if lease.may_begin_writing(begin_s):
        lease.hold("j1", active=True, writing=True, now_s=begin_s)
        t = begin_s
        while t + 0.5 < outage_s:  # started, then progress every 0.5 s, until the outage
            t += 0.5
            book.status(_status("uav1", "j1"), t)
            book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="progress"), t)
            lease.acknowledged("j1", t - delay_back_s)
        last_ink_s = _last_ink_s(lease, begin_s, writing_wall_s)
        if slowdown <= 1.0 + WRITING_SLOWDOWN:
            assert last_ink_s == begin_s + writing_wall_s  # written to its end, unheard
    else:
        last_ink_s = -math.inf  # the brush never went down

    if restart:
        book = Book(config, list(book.jobs.values()), now_s=outage_s + 0.5)
    else:
        book.liveliness("uav1", False, outage_s)
    first_free_s = _first_free_s(book, outage_s + 0.5, max(last_ink_s, outage_s) + 60.0)
    assert last_ink_s < first_free_s, (last_ink_s, first_free_s)


def test_the_fence_is_the_planned_writing_with_room_after_the_latest_ready_report() -> None:
    config = _config(time_scale=2.0)
    book = Book(config, now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    book.status(_status("uav1", None), 0.0)
    book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=1.0)
    ready = AgentReport(vehicle_id="uav1", job_id="j1", event="holding", planned_duration_s=20.0)
    book.report(ready, 10.0)
    book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="holding"), 11.0)  # a probe
    fence = writing_fence_s(config, book.jobs["j1"])
    assert fence == 10.0 + LOST_AFTER_S + 1.5 * 20.0 / 2.0  # 10 s of wall writing, +50 %
    book.report(ready, 12.0)  # sent again while the vehicle settled: later
    assert writing_fence_s(config, book.jobs["j1"]) == fence + 2.0
    lease = JobLease(LOST_AFTER_S, time_scale=2.0)
    lease.hold("j1", active=True, writing=False, now_s=9.9)
    assert not lease.may_begin_writing(9.9)  # no ready report acknowledged: no ink
    lease.acknowledged("j1", 9.9, 20.0)
    assert lease.may_begin_writing(9.9 + 1.4) and not lease.may_begin_writing(9.9 + 1.5)
    lease.hold("j1", active=True, writing=True, now_s=10.5)
    assert lease.breach(0.0, 9.9 + 16.4) is None and lease.breach(0.0, 9.9 + 16.6) is not None
    unacknowledged = JobLease(LOST_AFTER_S, time_scale=2.0)
    unacknowledged.hold("j1", active=True, writing=True, now_s=9.9)
    assert unacknowledged.breach(0.0, 9.9 + 1.6) is not None  # lost_after_s only


@settings(max_examples=300, deadline=None)
@given(
    planned_s=st.floats(2.0, 60.0),
    time_scale=st.sampled_from([1.0, 4.0, 6.0]),
    outage_after_s=st.floats(0.0, 40.0),
    killed=st.booleans(),
    measure_s=st.floats(0.0, 10.0),
    silence_s=st.one_of(st.none(), st.floats(0.0, 120.0)),
    restart=st.booleans(),
)
def test_a_character_written_in_full_is_never_given_to_another_vehicle(
    planned_s: float,
    time_scale: float,
    outage_after_s: float,
    killed: bool,
    measure_s: float,
    silence_s: float | None,
    restart: bool,
) -> None:
    """uav1 writes j1 from 10 s (its ready report acknowledged); ``outage_after_s`` later it is
    cut off (its agent SIGKILLed then, or only unheard; the orchestrator restarted or not) for
    ``silence_s`` (None: for good). Its writing, if it goes on, ends on plan; measuring it takes
    ``measure_s``; its agent keeps the result in the real journal on disk
    (``vehicle_agent/results.py``), which a restarted agent reads. The orchestrator (the real
    ``Book``) must not give j1 to uav2 if uav1 wrote it in full, however long uav1 stays
    silent; and once uav1 is back, j1 is settled: written by uav1, or given on."""
    config = _config(time_scale)
    book = Book(config, now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    book.status(_status("uav1", None, "first"), 0.0)
    book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=1.0)
    ready = AgentReport(
        vehicle_id="uav1", job_id="j1", event="holding", planned_duration_s=planned_s
    )
    book.status(_status("uav1", "j1", "first"), 10.0)
    assert book.report(ready, 10.0)[0].ok
    end_s = 10.0 + planned_s / time_scale
    cut_s = 10.0 + outage_after_s
    in_full = not killed or end_s <= cut_s
    measured = in_full and (not killed or end_s + measure_s <= cut_s)
    back_s = None if silence_s is None else cut_s + silence_s
    with tempfile.TemporaryDirectory() as folder:
        journal = ResultJournal("uav1", Path(folder))
        if in_full:
            journal.written("j1", planned_s)
        if measured:
            journal.measured(_DONE)
        if restart:
            book = Book(config, list(book.jobs.values()), now_s=cut_s)
        book.liveliness("uav1", False, cut_s)
        book.liveliness("uav2", True, cut_s)
        if killed:  # the new agent knows only what is on disk
            journal = ResultJournal("uav1", Path(folder))
            for result in journal.recover():
                assert result.job_id == "j1"
        t = cut_s
        last_news_s = max(cut_s if back_s is None else back_s, end_s + measure_s)
        while t < last_news_s + 60.0:
            t += 0.5
            book.tick(t)
            book.status(_status("uav2", _job_of(book, "uav2")), t)
            if back_s is not None and t >= back_s:
                if not book.vehicles["uav1"].alive:
                    book.liveliness("uav1", True, t)
                writing = not killed and t < end_s
                said = "j1" if writing else journal.pending()
                book.status(_status("uav1", said, "second" if killed else "first"), t)
                if not writing and said is not None and t >= end_s + measure_s:
                    result = _DONE if not killed else journal.recover()[0]
                    book.report(result, t)
                    journal.settled("j1")
            job = book.jobs["j1"]
            if in_full:
                assert job.vehicle_id == "uav1", (t, job)
        job = book.jobs["j1"]
        if back_s is None:
            assert job.state == "queued" if in_full else job.state in ("queued", "assigned")
        elif in_full:
            assert (job.state, job.vehicle_id) in {("done", "uav1"), ("failed", "uav1")}
        else:
            assert job.vehicle_id == "uav2" and job.state == "assigned"
            assert "b1" in book.dirty_boards  # half-written


_DONE = AgentReport(vehicle_id="uav1", job_id="j1", event="done", progress=1.0)


@settings(max_examples=300, deadline=None)
@given(
    planned_s=st.floats(2.0, 60.0),
    time_scale=st.sampled_from([1.0, 6.0]),
    stop_after_s=st.floats(0.0, 12.0),
    command=st.sampled_from(["estop", "land", "land_all"]),
    measure_s=st.floats(0.0, 5.0),
)
def test_an_operators_stop_as_the_writing_ends_never_has_the_character_written_again(
    planned_s: float, time_scale: float, stop_after_s: float, command: str, measure_s: float
) -> None:
    """uav1 writes j1 from 10 s (its ready report acknowledged); the operator stops it
    (``command``) ``stop_after_s`` later: while it writes, or after its writing ended while its
    result, measured in ``measure_s``, is on its way (before 2026-12-02 the job went to uav2 at
    once there, and the character was written twice in full).
    Written in full, j1 is uav1's until its result comes, and done by uav1; broken off, j1 goes
    to the next vehicle and uav1's board waits for a fresh sheet."""
    book = Book(_config(time_scale), now_s=0.0)
    for vid in ("uav1", "uav2"):
        book.liveliness(vid, True, 0.0)
    book.status(_status("uav1", None), 0.0)
    book.submit("j1", SubmitRequest(text="L"), label="L", estimate_s=9.0, now_s=1.0)
    ready = AgentReport(
        vehicle_id="uav1", job_id="j1", event="holding", planned_duration_s=planned_s
    )
    book.status(_status("uav1", "j1"), 10.0)
    assert book.report(ready, 10.0)[0].ok
    book.status(_status("uav2", None), 10.0)
    end_s = 10.0 + planned_s / time_scale
    stop_s = 10.0 + stop_after_s
    in_full = end_s <= stop_s
    vehicle = None if command == "land_all" else "uav1"
    assert book.operator(OperatorCommand(command=command, vehicle_id=vehicle), stop_s)[0].ok
    if command == "land_all":  # everyone down, then back to work
        for after in ("release_all", "resume"):
            assert book.operator(OperatorCommand(command=after), stop_s + 0.1)[0].ok
    t, reported = stop_s, False
    while t < stop_s + 30.0:
        t += 0.25
        book.tick(t)
        book.status(_status("uav2", _job_of(book, "uav2")), t)
        if in_full and not reported and t >= end_s + measure_s:
            reported = book.report(_DONE, t)[0].ok
        said = "j1" if in_full and not reported else None  # its journal names it till then
        book.status(_status("uav1", said), t)
        if in_full:
            assert book.jobs["j1"].vehicle_id == "uav1", (t, book.jobs["j1"])
    job = book.jobs["j1"]
    if in_full:
        assert (job.state, job.vehicle_id) == ("done", "uav1")
        assert "b1" not in book.dirty_boards
    else:
        assert job.vehicle_id == "uav2" and job.state == "assigned", job
        assert "b1" in book.dirty_boards  # half-written


def _job_of(book: Book, vehicle_id: str) -> str | None:
    job = book.active_job_of(vehicle_id)
    return None if job is None else job.job_id
