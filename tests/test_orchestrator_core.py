"""The orchestrator's pure state machine: scenarios and hypothesis properties."""

from __future__ import annotations

from collections import Counter

import msgspec
import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import (
    RuleBasedStateMachine,
    initialize,
    invariant,
    rule,
)

from bus.messages import (
    AgentReport,
    CommandReply,
    ErrorInfo,
    Event,
    JobMetrics,
    JobStateName,
    OperatorCommand,
    SubmitRequest,
    VehicleStatus,
)
from orchestrator import holders
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo, VehicleView, ready_for_job
from orchestrator.jobs import (
    FINAL_STATES,
    TRANSITIONS,
    Job,
    TransitionError,
    to_state,
    transition,
)

# three vehicles, two of them share board b2
VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
    VehicleInfo("uav3", "quadrotor-brush", "b2"),
)
METRICS = JobMetrics(rmse_pen_down_m=0.01, rmse_m=0.01, max_error_m=0.02, iou=0.9, duration_s=9)


def _config(**kw: object) -> CoreConfig:
    return CoreConfig(show_id="t", vehicles=VEHICLES, **kw)  # type: ignore[arg-type]


def _submit(book: Book, job_id: str, now: float, priority: int = 0) -> Effects:
    reply, eff = book.submit(
        job_id, SubmitRequest(text="L", priority=priority), label="L", estimate_s=20.0, now_s=now
    )
    assert reply.ok, reply
    return eff


def _online(book: Book, vid: str, now: float) -> Effects:
    eff = book.liveliness(vid, True, now)
    more = book.status(VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="idle"), now)
    eff.commands += more.commands
    eff.jobs.update(more.jobs)
    return eff


def _assigned(eff: Effects) -> list[tuple[str, str]]:
    return [(vid, c.job.job_id) for vid, c in eff.commands if c.command == "assign" and c.job]


def test_transition_table_is_closed_and_final_states_are_final() -> None:
    for state, nexts in TRANSITIONS.items():
        assert nexts <= set(TRANSITIONS)
        assert (state in FINAL_STATES) == (not nexts)
    book = Book(_config(), now_s=0.0)
    _submit(book, "j1", 0.0)
    with pytest.raises(TransitionError):
        transition(book.jobs["j1"], "writing", 1.0)


def test_fifo_with_priorities_and_one_job_per_board() -> None:
    book = Book(_config(), now_s=0.0)
    for i, prio in enumerate([0, 0, 5, 0]):
        _submit(book, f"j{i}", float(i), priority=prio)
    assert [j.job_id for j in book.queue()] == ["j2", "j0", "j1", "j3"]
    etas = book.etas(10.0)
    assert etas["j2"] == (1, None)  # no vehicle usable yet: no ETA
    got = _assigned(_online(book, "uav1", 10.0))
    got += _assigned(_online(book, "uav2", 10.0))
    got += _assigned(_online(book, "uav3", 10.0))  # shares b2 with uav2: nothing for it
    assert got == [("uav1", "j2"), ("uav2", "j0")]
    positions = book.etas(10.0)
    assert positions["j1"][0] == 1 and positions["j3"][0] == 2
    eta1, eta3 = positions["j1"][1], positions["j3"][1]
    assert eta1 is not None and eta3 is not None and 0 < eta1 <= eta3


def test_moderated_job_waits_for_approval_then_runs_to_done() -> None:
    book = Book(_config(moderation=True), now_s=0.0)
    _online(book, "uav1", 0.0)
    reply, eff = book.submit("j1", SubmitRequest(text="一"), label="一", estimate_s=5, now_s=1)
    assert reply.state == "awaiting_approval" and reply.queue_position is None
    assert not _assigned(eff)
    ok, eff = book.operator(OperatorCommand(command="approve", job_id="j1"), 2.0)
    assert ok.ok and _assigned(eff) == [("uav1", "j1")]
    ack, _ = book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="started"), 3.0)
    assert ack.ok and book.jobs["j1"].state == "writing"
    rep = AgentReport(vehicle_id="uav1", job_id="j1", event="done", metrics=METRICS)
    assert book.report(rep, 4.0)[0].ok
    assert book.report(rep, 4.5)[0].message == "job already done"  # retried report: idempotent
    job = book.jobs["j1"]
    assert (job.state, job.metrics, job.attempts) == ("done", METRICS, 1)


def test_lost_vehicle_job_is_requeued_and_finished_by_another() -> None:
    book = Book(_config(lost_after_s=1.5), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.5)
    assert book.jobs["j1"].vehicle_id == "uav1"
    book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="started"), 1.0)
    book.liveliness("uav1", False, 2.0)
    assert book.tick(3.0).jobs == {}  # within the grace period
    eff = book.tick(3.5)
    assert eff.jobs["j1"].state == "queued" and eff.jobs["j1"].error.code == "vehicle_lost"
    assert any(e.kind == "vehicle_lost" for e in eff.events)
    assert _assigned(_online(book, "uav2", 4.0)) == []  # it waits for uav1 (holders.py)
    eff = book.tick(3.5 + book.config.lost_job_hold_s)
    assert _assigned(eff) == [] and [e.kind for e in eff.events] == ["job_waits"]
    sheet = OperatorCommand(command="fresh_sheet", board_id="b1")  # uav1 did not write it all
    reply, eff = book.operator(sheet, 4.0 + book.config.lost_job_hold_s)
    assert reply.ok and _assigned(eff) == [("uav2", "j1")] and book.jobs["j1"].attempts == 2
    assert [e.kind for e in eff.events if e.level == "warning"] == ["job_released"]
    # the old vehicle's late progress is refused and it is told to stop
    book.liveliness("uav1", True, 9.0)
    reply, eff = book.report(AgentReport(vehicle_id="uav1", job_id="j1", event="progress"), 9.2)
    assert not reply.ok and reply.error.code == "not_assigned"
    assert [(v, c.command) for v, c in eff.commands] == [("uav1", "cancel")]


def test_job_fails_after_max_attempts_of_lost_vehicles() -> None:
    book = Book(_config(max_attempts=2, lost_after_s=1.0), now_s=0.0)
    _submit(book, "j1", 0.0)
    now = 0.0
    for attempt in (1, 2):
        now += 1.0
        _online(book, "uav1", now)  # the second time: back without it, it waits a back-off
        now += book.config.refuse_backoff_s
        book.tick(now)
        assert book.jobs["j1"].attempts == attempt
        book.liveliness("uav1", False, now + 0.1)
        book.tick(now + 1.2)
        now += 2.0
    assert book.jobs["j1"].state == "failed"


def test_restart_requeues_unconfirmed_jobs_and_keeps_confirmed_ones() -> None:
    book = Book(_config(), now_s=0.0)
    for vid in ("uav1", "uav2"):
        _online(book, vid, 0.0)
    _submit(book, "j1", 0.0)
    _submit(book, "j2", 0.0)
    restarted = Book(_config(lost_after_s=1.5), book.jobs.values(), now_s=100.0)
    # uav1 is back and still writing j1; uav2 never comes back
    restarted.liveliness("uav1", True, 100.2)
    status = VehicleStatus(vehicle_id="uav1", kind="q", state="writing", job_id="j1")
    restarted.status(status, 100.3)
    eff = restarted.tick(102.0)
    assert restarted.jobs["j1"].state == "assigned"
    assert eff.jobs["j2"].state == "queued"


def test_vehicle_that_forgot_its_job_gives_it_back_after_the_grace() -> None:
    book = Book(_config(confirm_grace_s=3.0), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.0)
    idle = VehicleStatus(vehicle_id="uav1", kind="q", state="idle")
    book.status(idle, 1.0)
    book.status(idle, 2.0)
    assert book.jobs["j1"].state == "assigned"
    eff = book.status(idle, 4.1)
    job = eff.jobs["j1"]
    assert (job.state, job.attempts, job.counted_attempts) == ("queued", 1, 0)  # not its fault
    assert "is not writing it" in eff.events[-1].message
    assert not _assigned(book.tick(5.0))  # the vehicle backs off
    eff = book.tick(4.1 + book.config.refuse_backoff_s + 0.1)
    assert _assigned(eff) == [("uav1", "j1")] and eff.jobs["j1"].attempts == 2


def test_jobs_given_up_unconfirmed_by_present_vehicles_count_no_attempt_but_are_bounded() -> None:
    """Under CPU overload agents give jobs up for lack of acknowledgement (their lease): such a
    job must not fail after ``max_attempts`` (nothing is wrong with it), nor go round for ever."""
    book = Book(_config(max_attempts=3, max_handbacks=5, confirm_grace_s=3.0), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.0)
    idle = VehicleStatus(vehicle_id="uav1", kind="q", state="idle")
    now, states = 0.0, []
    for _ in range(5):
        assert book.jobs["j1"].state == "assigned"
        book.status(idle, now + 0.1)  # given up: its status names no job
        now += 3.2
        eff = book.status(idle, now)
        states.append((eff.jobs["j1"].state, eff.jobs["j1"].handbacks))
        now += book.config.refuse_backoff_s + 0.1
        book.status(idle, now)
        book.tick(now)
    assert states == [("queued", 1), ("queued", 2), ("queued", 3), ("queued", 4), ("failed", 5)]
    assert "gave up after 5 hand-backs" in eff.events[-1].message


def test_lost_attempts_and_hand_backs_are_bounded_apart() -> None:
    book = Book(_config(max_attempts=2, max_handbacks=3, lost_after_s=1.0), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.0)
    book.assignment_result("uav1", "j1", None, 0.1)  # unanswered: a hand-back
    assert _assigned(book.tick(2.2)) == [("uav1", "j1")]
    book.assignment_result("uav1", "j1", None, 2.3)
    assert (book.jobs["j1"].attempts, book.jobs["j1"].handbacks) == (2, 2)
    book.tick(4.5)
    assert book.jobs["j1"].state == "assigned"
    book.liveliness("uav1", False, 4.6)
    book.tick(5.7)  # lost: a counted attempt, not a hand-back
    job = book.jobs["j1"]
    assert (job.state, job.attempts, job.handbacks, job.counted_attempts) == ("queued", 3, 2, 1)


def test_refused_assignment_goes_back_to_the_queue_without_an_attempt() -> None:
    book = Book(_config(), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.0)
    eff = book.assignment_result("uav1", "j1", CommandReply(ok=False, message="busy"), 0.1)
    assert eff.jobs["j1"].state == "queued" and eff.jobs["j1"].counted_attempts == 0
    assert not _assigned(eff)  # backing off
    assert _assigned(book.tick(2.2)) == [("uav1", "j1")]


def test_refused_takeoff_requeues_the_job_and_backs_the_vehicle_off() -> None:
    book = Book(_config(), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.0)
    error = ErrorInfo(code="takeoff_refused", message="PreArm: Compass not calibrated")
    refused = AgentReport(
        vehicle_id="uav1", job_id="j1", event="failed", error=error, retry_after_s=5.0
    )
    reply, eff = book.report(refused, 1.0)
    job = eff.jobs["j1"]
    assert reply.ok and (job.state, job.counted_attempts) == ("queued", 0)
    assert "Compass" in eff.events[-1].message and eff.events[-1].kind == "job_requeued"
    assert not _assigned(book.tick(5.9))  # the vehicle is backing off
    eff = book.tick(6.1)
    assert _assigned(eff) == [("uav1", "j1")] and eff.jobs["j1"].counted_attempts == 1
    plain = AgentReport(vehicle_id="uav1", job_id="j1", event="failed", error=error)
    assert book.report(plain, 7.0)[1].jobs["j1"].state == "failed"  # no retry: the job failed


def test_a_vehicle_waiting_for_its_pre_arm_checks_gets_no_job_until_they_pass() -> None:
    book = Book(_config(), now_s=0.0)
    book.liveliness("uav1", True, 0.0)
    why = "Preflight Fail: horizontal velocity unstable"
    waiting = VehicleStatus(vehicle_id="uav1", kind="quadrotor-brush", state="idle", preflight=why)
    book.status(waiting, 0.1)
    view = book.vehicles["uav1"]
    assert not ready_for_job(view, 0.1)
    assert not _assigned(_submit(book, "j1", 0.2))
    assert not _assigned(book.tick(40.0)) and not _assigned(book.status(waiting, 40.0))
    (summary,) = [v for v in book.snapshot(40.0).vehicles if v.vehicle_id == "uav1"]
    assert summary.message == f"held by its preflight: {why}"
    job = book.jobs["j1"]
    assert (job.state, job.attempts, view.refused_until_s) == ("queued", 0, 0.0)  # no back-off
    ready = msgspec.structs.replace(waiting, preflight="")
    assert _assigned(book.status(ready, 41.0)) == [("uav1", "j1")]  # at once, not at a tick


def test_ready_for_job_needs_the_pre_arm_checks_passing() -> None:
    view = VehicleView(VEHICLES[0], alive=True, lost=False, state="idle", status_at_s=0.0)
    view.preflight = "PreArm: Need Position Estimate"
    assert not ready_for_job(view, 1.0)
    view.preflight = ""
    assert ready_for_job(view, 1.0)


def test_a_job_aborted_before_writing_counts_its_attempts_and_fails_at_the_limit() -> None:
    book = Book(_config(max_attempts=3), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.0)
    error = ErrorInfo(code="not_settled", message="not settled within 1 cm after 3 approaches")
    now, states = 0.0, []
    for _ in range(3):
        assert book.jobs["j1"].state == "assigned"
        aborted = AgentReport(
            vehicle_id="uav1", job_id="j1", event="failed", error=error, retry_after_s=1.0
        )
        reply, eff = book.report(aborted, now + 0.5)
        assert reply.ok
        states.append((eff.jobs["j1"].state, eff.jobs["j1"].attempts))
        now += 2.0
        book.tick(now)
    assert states == [("queued", 1), ("queued", 2), ("failed", 3)]  # not round for ever
    assert eff.events[-1].kind == "job_failed" and "gave up after 3 tries" in eff.events[-1].message


def test_vehicle_events_are_relayed_with_the_orchestrators_time_and_rate_limited() -> None:
    book = Book(_config(), now_s=0.0)
    said = Event(time_s=123.0, level="alert", kind="autopilot", message="PreArm: Need GPS")
    eff = book.vehicle_event("uav1", said, 50.0)
    assert [(e.time_s, e.vehicle_id, e.level, e.message) for e in eff.events] == [
        (50.0, "uav1", "alert", "PreArm: Need GPS")
    ]
    assert not book.vehicle_event("nobody", said, 50.0).events
    relayed = sum(len(book.vehicle_event("uav2", said, 60.0).events) for _ in range(30))
    assert relayed == 10  # a burst, then the rate limit
    assert len(book.vehicle_event("uav2", said, 62.0).events) == 1
    assert book.vehicle_event("uav1", said, 62.0).events  # per vehicle


def test_waiting_drawings_carry_their_strokes_within_the_budget() -> None:
    book = Book(_config(), now_s=0.0)
    strokes = {"units": "m", "strokes": [[[0.0, 0.0], [0.1, 0.2]]]}
    for job_id in ("j1", "j2"):
        request = SubmitRequest(strokes=strokes)
        book.submit(job_id, request, label="drawing", estimate_s=5.0, now_s=0.0)
    size = len(msgspec.json.encode(strokes))
    snap = book.snapshot(1.0, strokes_budget_bytes=size + 1)
    assert [j.strokes for j in snap.jobs] == [strokes, None]  # oldest first, then out of budget
    assert all(j.strokes is None for j in book.snapshot(1.0, include_final=False).jobs)
    _online(book, "uav1", 2.0)  # j1 is assigned: no longer waiting
    snap = book.snapshot(3.0, strokes_budget_bytes=10 * size)
    assert [(j.state, j.strokes) for j in snap.jobs] == [("assigned", None), ("queued", strokes)]
    assert to_state(book.jobs["j1"], with_strokes=True).strokes is None


def test_operator_commands() -> None:
    book = Book(_config(), now_s=0.0)
    _online(book, "uav1", 0.0)
    _submit(book, "j1", 0.0)
    _submit(book, "j2", 0.0)
    reply, _ = book.operator(OperatorCommand(command="cancel", job_id="nope"), 1.0)
    assert reply.error is not None and reply.error.code == "unknown_job"
    reply, _ = book.operator(OperatorCommand(command="land"), 1.0)
    assert reply.error is not None and reply.error.field == "vehicle_id"
    reply, eff = book.operator(OperatorCommand(command="land", vehicle_id="uav1"), 1.0)
    assert reply.ok and ("uav1", "land") in [(v, c.command) for v, c in eff.commands]
    assert book.jobs["j1"].state == "queued" and book.vehicles["uav1"].paused
    book.operator(OperatorCommand(command="prioritize", job_id="j2", priority=3), 1.5)
    assert [j.job_id for j in book.queue()] == ["j2", "j1"]
    book.operator(OperatorCommand(command="cancel", job_id="j1"), 2.0)
    assert book.jobs["j1"].state == "cancelled"
    reply, eff = book.operator(OperatorCommand(command="resume"), 3.0)
    assert _assigned(eff) == []  # landed: held until released
    reply, eff = book.operator(OperatorCommand(command="release", vehicle_id="uav1"), 3.0)
    assert _assigned(eff) == [("uav1", "j2")]
    reply, eff = book.operator(OperatorCommand(command="estop"), 4.0)
    assert book.queue_paused and all(v.paused for v in book.vehicles.values())
    assert {c.command for _, c in eff.commands} == {"estop"}
    assert book.jobs["j2"].state == "queued"
    assert eff.events[-1].level == "alert"


def test_positions_of_other_jobs_are_published_after_prioritize_cancel_and_assign() -> None:
    book = Book(_config(), now_s=0.0)
    for i in range(1, 5):
        eff = _submit(book, f"j{i}", float(i))
        assert eff.jobs.keys() == {f"j{i}"} and not eff.moved  # appended: nobody else moved
    reply, eff = book.operator(OperatorCommand(command="prioritize", job_id="j3", priority=5), 5)
    assert reply.ok and eff.jobs.keys() == {"j3"}
    assert [e.message for e in eff.events] == ["operator: prioritize j3 to 5"]  # the new value
    assert eff.moved == {"j1", "j2"}  # j4 stays 4th
    assert [j.job_id for j in book.queue()] == ["j3", "j1", "j2", "j4"]
    reply, eff = book.operator(OperatorCommand(command="cancel", job_id="j1"), 6.0)
    assert reply.ok and eff.jobs.keys() == {"j1"} and eff.moved == {"j2", "j4"}
    eff = _online(book, "uav1", 7.0)  # j3 assigned; j2, j4 move up and get an ETA
    assert _assigned(eff) == [("uav1", "j3")]
    more = book.status(VehicleStatus(vehicle_id="uav1", kind="q", state="idle"), 7.0)
    assert not more.moved  # nothing changed since the last decision
    assert book.tick(7.5).moved == set()  # an ETA that only counts down is not a change
    reply, eff = book.operator(OperatorCommand(command="reject", job_id="j4"), 8.0)
    assert reply.error is not None and reply.error.code == "bad_state" and not eff.moved


def test_approve_and_reject_replies_say_what_happened() -> None:
    book = Book(_config(moderation=True), now_s=0.0)
    _submit(book, "j1", 0.0)
    _submit(book, "j2", 0.0)
    reply, _ = book.operator(OperatorCommand(command="approve", job_id="j1"), 1.0)
    assert reply.message == "j1 approved"
    reply, _ = book.operator(OperatorCommand(command="reject", job_id="j2"), 1.0)
    assert reply.message == "j2 rejected"


def test_queue_full_is_refused() -> None:
    book = Book(_config(max_queue=2), now_s=0.0)
    _submit(book, "j1", 0.0)
    _submit(book, "j2", 0.0)
    reply, _ = book.submit("j3", SubmitRequest(text="L"), label="L", estimate_s=1, now_s=0)
    assert not reply.ok and reply.error.code == "queue_full" and "j3" not in book.jobs


def _finished_job(seq: int, state: JobStateName) -> Job:
    return Job(
        job_id=f"old{seq}",
        seq=seq,
        state=state,
        kind="text",
        text="L",
        label="L",
        client_id="c",
        created_at_s=float(seq),
        updated_at_s=float(seq),
    )


def test_job_counts_stay_exact_past_the_finished_jobs_listed() -> None:
    old = [_finished_job(k + 1, "failed" if k % 100 == 0 else "done") for k in range(620)]
    book = Book(_config(), old, now_s=1000.0)
    _submit(book, "new1", 1000.0)
    snap = book.snapshot(1000.0)
    assert sum(1 for j in snap.jobs if j.state in FINAL_STATES) == 500  # the list is bounded
    assert snap.job_counts == {"done": 613, "failed": 7, "queued": 1}
    assert book.snapshot(1000.0, include_final=False).job_counts == snap.job_counts
    eff = _online(book, "uav1", 1001.0)
    assert _assigned(eff) == [("uav1", "new1")]
    report = AgentReport(vehicle_id="uav1", job_id="new1", event="done", metrics=METRICS)
    book.report(report, 1010.0)
    assert book.snapshot(1010.0).job_counts == {"done": 614, "failed": 7}


# --- properties ---------------------------------------------------------------------------------


class FleetMachine(RuleBasedStateMachine):
    """Random submissions, agents (that take, write, forget or lose jobs), operator and time."""

    @initialize(moderation=st.booleans())
    def start(self, moderation: bool) -> None:
        config = _config(moderation=moderation, max_attempts=3, max_handbacks=4)
        self.book = Book(config, now_s=0.0)
        self.now = 0.0
        self.submitted: list[str] = []
        self.agent_job: dict[str, str | None] = {v.vehicle_id: None for v in VEHICLES}
        self.final_seen: dict[str, object] = {}
        self.seen_placing: dict[str, tuple[int, float | None]] = {}
        """What a subscriber of jobs/* knows: queue position and expected start time [s]."""
        self.holds: dict[str, tuple[str, float]] = {}
        """Queued job -> the lost vehicle it waits for, and until when [s]."""

    def _apply(self, eff: Effects, queued_before: list[str] | None = None) -> None:
        placings = self.book.etas(self.now)
        assert not eff.moved & eff.jobs.keys()
        for job_id in eff.jobs.keys() | eff.moved:  # what the service publishes
            if job_id in placings:
                position, eta = placings[job_id]
                self.seen_placing[job_id] = (position, None if eta is None else self.now + eta)
            else:
                self.seen_placing.pop(job_id, None)
        for vid, cmd in eff.commands:
            if cmd.command == "assign" and cmd.job is not None:
                if self.book.vehicles[vid].alive:
                    self.agent_job[vid] = cmd.job.job_id
            elif cmd.command in ("cancel", "land", "estop"):
                self.agent_job[vid] = None
        for job_id, job in eff.jobs.items():
            assert self.book.jobs[job_id] == job
        hold_s = self.book.config.lost_job_hold_s
        for e in eff.events:  # requeued for a lost vehicle (and maybe assigned in the same step)
            if e.kind == "job_requeued" and "waits" in e.message and e.job_id and e.vehicle_id:
                self.holds[e.job_id] = (e.vehicle_id, self.now + hold_s)
            elif e.kind == "job_released" and e.job_id:  # its vehicle came back without it
                self.holds.pop(e.job_id, None)
        for vid, cmd in eff.commands:  # a job waiting for a lost vehicle is given to nobody
            if cmd.command == "assign" and cmd.job is not None and cmd.job.job_id in self.holds:
                holder, until_s = self.holds[cmd.job.job_id]
                assert self.now >= until_s, (cmd.job.job_id, vid, holder)
        self.holds = {
            j.job_id: (j.vehicle_id, j.holder_hold_until_s)
            for j in self.book.queue()
            if j.holder_hold_until_s is not None and j.vehicle_id is not None
        }
        remaining = self.book.queue()
        for _, cmd in eff.commands:  # in queue order, among the jobs that may be given
            if cmd.command == "assign" and cmd.job is not None:
                key = self.book.jobs[cmd.job.job_id].sort_key
                takes = [j for j in remaining if holders.assignable(j, self.now)]
                assert all(j.sort_key > key for j in takes), "queue order not respected"

    @rule(priority=st.integers(0, 2))
    def submit(self, priority: int) -> None:
        job_id = f"j{len(self.submitted)}"
        req = SubmitRequest(text="L", priority=priority)
        reply, eff = self.book.submit(job_id, req, label="L", estimate_s=10, now_s=self.now)
        if reply.ok:
            self.submitted.append(job_id)
        self._apply(eff)

    @rule(data=st.data(), command=st.sampled_from(["approve", "reject", "cancel", "prioritize"]))
    def job_command(self, data: st.DataObject, command: str) -> None:
        if not self.submitted:
            return
        job_id = data.draw(st.sampled_from(self.submitted))
        cmd = OperatorCommand(command=command, job_id=job_id, priority=data.draw(st.integers(0, 3)))
        self._apply(self.book.operator(cmd, self.now)[1])

    @rule(
        vid=st.sampled_from([v.vehicle_id for v in VEHICLES]),
        command=st.sampled_from(
            ["pause", "resume", "resume", "land", "estop", "land_all", "release"]
        ),
        whole=st.booleans(),
    )
    def fleet_command(self, vid: str, command: str, whole: bool) -> None:
        target = None if whole and command != "land" else vid
        self._apply(
            self.book.operator(OperatorCommand(command=command, vehicle_id=target), self.now)[1]
        )

    @rule(vid=st.sampled_from([v.vehicle_id for v in VEHICLES]), forget=st.booleans())
    def liveliness_flip(self, vid: str, forget: bool) -> None:
        alive = not self.book.vehicles[vid].alive
        if not alive and forget:
            self.agent_job[vid] = None  # process killed: it forgets its job
        self._apply(self.book.liveliness(vid, alive, self.now))

    @rule(vid=st.sampled_from([v.vehicle_id for v in VEHICLES]))
    def online(self, vid: str) -> None:
        self._apply(self.book.liveliness(vid, True, self.now))
        self.status(vid)

    @rule(vid=st.sampled_from([v.vehicle_id for v in VEHICLES]))
    def status(self, vid: str) -> None:
        if not self.book.vehicles[vid].alive:
            return
        job = self.agent_job[vid]
        st_ = VehicleStatus(
            vehicle_id=vid, kind="q", state="writing" if job else "idle", job_id=job
        )
        self._apply(self.book.status(st_, self.now))

    @rule(
        vid=st.sampled_from([v.vehicle_id for v in VEHICLES]),
        event=st.sampled_from(["holding", "started", "progress", "done", "failed"]),
    )
    def report(self, vid: str, event: str) -> None:
        job = self.agent_job[vid]
        if job is None:
            return
        rep = AgentReport(vehicle_id=vid, job_id=job, event=event, progress=0.5)
        reply, eff = self.book.report(rep, self.now)
        if event in ("done", "failed") or not reply.ok:
            self.agent_job[vid] = None
        self._apply(eff)

    @rule(data=st.data(), vid=st.sampled_from([v.vehicle_id for v in VEHICLES]))
    def ended(self, data: st.DataObject, vid: str) -> None:
        """An ``ended`` report (what was written of a job stopped otherwise: issue 34), about any
        job, from any vehicle, at any time: no job's state changes, no command goes out."""
        if not self.submitted:
            return
        job_id = data.draw(st.sampled_from(self.submitted))
        before = {j.job_id: msgspec.structs.replace(j, metrics=None, updated_at_s=0.0)
                  for j in self.book.jobs.values()}  # fmt: skip
        info = ErrorInfo(code="cancelled", message="cancelled at 50% of its plan")
        rep = AgentReport(vehicle_id=vid, job_id=job_id, event="ended", progress=0.5, error=info)
        reply, eff = self.book.report(rep, self.now)
        assert reply.ok and eff.commands == []
        after = {j.job_id: msgspec.structs.replace(j, metrics=None, updated_at_s=0.0)
                 for j in self.book.jobs.values()}  # fmt: skip
        assert after == before
        self._apply(eff)

    @rule(vid=st.sampled_from([v.vehicle_id for v in VEHICLES]), answered=st.booleans())
    def refuse(self, vid: str, answered: bool) -> None:
        job = self.book.active_job_of(vid)
        if job is None or job.state != "assigned":
            return
        self.agent_job[vid] = None
        reply = CommandReply(ok=False, message="busy") if answered else None
        self._apply(self.book.assignment_result(vid, job.job_id, reply, self.now))

    @rule(dt=st.sampled_from([0.1, 0.5, 1.0, 2.0, 4.0]))
    def tick(self, dt: float) -> None:
        self.now += dt
        self._apply(self.book.tick(self.now))

    @invariant()
    def no_job_lost_or_duplicated(self) -> None:
        if not hasattr(self, "book"):
            return
        assert sorted(self.book.jobs) == sorted(self.submitted)
        seqs = [j.seq for j in self.book.jobs.values()]
        assert len(seqs) == len(set(seqs))
        counts = Counter(j.state for j in self.book.jobs.values())
        assert self.book.snapshot(self.now, max_final=2).job_counts == dict(counts)

    @invariant()
    def subscribers_know_every_queue_position_and_eta(self) -> None:
        if not hasattr(self, "book"):
            return
        tolerance_s = self.book.config.eta_tolerance_s
        for job_id, (position, eta) in self.book.etas(self.now).items():
            seen = self.seen_placing.get(job_id)
            assert seen is not None and seen[0] == position, (job_id, seen, position)
            start = None if eta is None else self.now + eta
            if start is None or seen[1] is None:
                assert start is seen[1], (job_id, seen, start)
            else:
                assert abs(start - seen[1]) <= tolerance_s + 1e-9, (job_id, seen, start)

    @invariant()
    def hand_backs_are_bounded(self) -> None:
        if not hasattr(self, "book"):
            return
        limit = self.book.config.max_handbacks
        for job in self.book.jobs.values():
            assert 0 <= job.handbacks <= limit and job.attempts >= 0, job
            assert job.handbacks < limit or job.state == "failed", job

    @invariant()
    def one_job_per_vehicle_and_board(self) -> None:
        if not hasattr(self, "book"):
            return
        active = [j for j in self.book.jobs.values() if j.active]
        vehicles = [j.vehicle_id for j in active]
        boards = [j.board_id for j in active]
        assert len(vehicles) == len(set(vehicles)) and None not in vehicles
        assert len(boards) == len(set(boards))
        # the Book's index of active jobs answers as a scan of every job would
        assert self.book.active_jobs() == sorted(active, key=lambda j: j.seq)
        for vid in self.book.vehicles:
            assert self.book.active_job_of(vid) == next(
                (j for j in active if j.vehicle_id == vid), None
            )

    @invariant()
    def active_jobs_are_on_vehicles_not_yet_lost(self) -> None:
        if not hasattr(self, "book"):
            return
        lost_after = self.book.config.lost_after_s
        for job in self.book.jobs.values():
            if job.active:
                view = self.book.vehicles[job.vehicle_id or ""]
                gone = view.gone_since_s
                assert view.alive or (gone is not None and self.now - gone < lost_after)

    @invariant()
    def final_states_stay_final(self) -> None:
        if not hasattr(self, "book"):
            return
        for job_id, seen in self.final_seen.items():
            assert self.book.jobs[job_id] == seen
        for job in self.book.jobs.values():
            assert job.counted_attempts <= 3
            if job.final:
                self.final_seen.setdefault(job.job_id, job)

    @invariant()
    def no_ready_vehicle_left_idle_with_work_waiting(self) -> None:
        if not hasattr(self, "book") or self.book.queue_paused or not self.book.queue():
            return
        closed_boards = self.book.busy_boards() | self.book.dirty_boards  # dirty: fresh sheet first
        for vid, view in self.book.vehicles.items():
            takes = [j for j in self.book.queue() if holders.assignable(j, self.now)]
            if not takes or self.book.active_job_of(vid) is not None:
                continue
            if view.info.board_id not in closed_boards:
                assert not ready_for_job(view, self.now)

    @invariant()
    def the_book_knows_which_job_waits_for_which_vehicle(self) -> None:
        if not hasattr(self, "book"):
            return
        for vid in self.book.vehicles:
            waiting = [
                j
                for j in self.book.queue()
                if j.vehicle_id == vid and j.holder_hold_until_s is not None
            ]
            assert self.book.awaited_by(vid) == (waiting[0] if waiting else None)


TestFleetMachine = FleetMachine.TestCase
TestFleetMachine.settings = settings(
    max_examples=150,
    stateful_step_count=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
