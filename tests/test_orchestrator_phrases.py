"""Phrases written together (``orchestrator/phrases.py``): scenarios and hypothesis properties
of the pure Book."""

from __future__ import annotations

from pathlib import Path
from typing import Literal

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st
from hypothesis.stateful import RuleBasedStateMachine, initialize, invariant, rule

from bus.messages import (
    AgentReport,
    CommandReply,
    ErrorInfo,
    OperatorCommand,
    SubmitRequest,
    VehicleStateName,
    VehicleStatus,
)
from orchestrator.core import Book, CoreConfig, Effects
from orchestrator.fleet import VehicleInfo
from orchestrator.jobs import Job
from orchestrator.quotas import QuotaPolicy, SubmitQuotas
from orchestrator.submissions import SubmissionError, validate_submission
from showfile import load_show

AIRSHOW = Path(__file__).resolve().parents[1] / "shows" / "airshow-2014.yaml"
# four boards in a row; uav5 shares b2 with uav2
VEHICLES = (
    VehicleInfo("uav1", "quadrotor-brush", "b1"),
    VehicleInfo("uav2", "quadrotor-brush", "b2"),
    VehicleInfo("uav3", "quadrotor-brush", "b3"),
    VehicleInfo("uav4", "quadrotor-brush", "b4"),
    VehicleInfo("uav5", "quadrotor-brush", "b2"),
)
ROW = ["b1", "b2", "b3", "b4"]


def _book(vehicles: tuple[VehicleInfo, ...] = VEHICLES[:4], **kw: object) -> Book:
    return Book(CoreConfig(show_id="t", vehicles=vehicles, **kw), now_s=0.0)  # type: ignore[arg-type]


def _online(book: Book, vid: str, now: float) -> Effects:
    book.liveliness(vid, True, now)
    return book.status(VehicleStatus(vehicle_id=vid, kind="quadrotor-brush", state="idle"), now)


def _phrase(book: Book, text: str, now: float, first: str = "p") -> tuple[list[str], Effects]:
    ids = [f"{first}{i}" for i in range(len(text))]
    reply, eff = book.submit_phrase(
        ids, SubmitRequest(text=text, phrase=True), [10.0] * len(ids), now_s=now
    )
    assert reply.ok and reply.job_id == ids[0], reply
    return ids, eff


def _assigned(eff: Effects) -> dict[str, str]:
    return {c.job.job_id: vid for vid, c in eff.commands if c.command == "assign" and c.job}


def _ready(book: Book, vid: str, job_id: str, now: float) -> CommandReply:
    rep = AgentReport(vehicle_id=vid, job_id=job_id, event="holding", planned_duration_s=8.0)
    return book.report(rep, now)[0]


def test_a_phrase_goes_to_adjacent_boards_in_reading_order_all_at_once() -> None:
    book = _book()
    for vid in ("uav1", "uav2", "uav3", "uav4"):
        _online(book, vid, 0.0)
    ids, eff = _phrase(book, "新年快乐", 1.0)
    assert _assigned(eff) == dict(zip(ids, ["uav1", "uav2", "uav3", "uav4"], strict=True))
    assert [book.jobs[j].text for j in ids] == list("新年快乐")
    assert [book.jobs[j].phrase.index for j in ids] == [0, 1, 2, 3]  # type: ignore[union-attr]


def test_a_phrase_waits_for_enough_free_boards_and_holds_back_the_queue_behind() -> None:
    book = _book()
    for vid in ("uav1", "uav2", "uav3", "uav4"):
        _online(book, vid, 0.0)
    book.submit("s1", SubmitRequest(text="永"), label="永", estimate_s=20.0, now_s=0.5)
    assert book.jobs["s1"].vehicle_id == "uav1"
    ids, eff = _phrase(book, "新年快乐", 1.0)
    assert _assigned(eff) == {}  # three boards free: nothing written piecemeal
    _, eff = book.submit("s2", SubmitRequest(text="光"), label="光", estimate_s=5, now_s=1.5)
    assert _assigned(eff) == {}  # the phrase ahead keeps b2-b4 for itself
    etas = book.etas(2.0)
    starts = {etas[j][1] for j in ids}
    assert len(starts) == 1 and None not in starts  # one start for all four characters
    (start,) = starts
    assert start is not None and start > book.config.eta.before_write_s  # after s1 is written
    eta_s2 = etas["s2"][1]
    assert eta_s2 is not None and eta_s2 > start  # behind the phrase
    done = AgentReport(vehicle_id="uav1", job_id="s1", event="done")
    _, eff = book.report(done, 30.0)  # uav1 idle by its last status: all four go at once
    assert _assigned(eff) == dict(zip(ids, ["uav1", "uav2", "uav3", "uav4"], strict=True))
    eff = book.report(AgentReport(vehicle_id="uav2", job_id=ids[1], event="done"), 50.0)[1]
    assert _assigned(eff) == {"s2": "uav2"}


def test_a_phrase_shorter_than_the_row_takes_the_leftmost_free_window() -> None:
    book = _book()
    for vid in ("uav1", "uav2", "uav3", "uav4"):
        _online(book, vid, 0.0)
    book.submit("s1", SubmitRequest(text="永"), label="永", estimate_s=20.0, now_s=0.5)
    book.submit("s2", SubmitRequest(text="永"), label="永", estimate_s=20.0, now_s=0.6)
    book.operator(OperatorCommand(command="cancel", job_id="s1"), 0.7)  # uav1 lands, b2 busy
    ids, eff = _phrase(book, "你好", 1.0)
    assert _assigned(eff) == dict(zip(ids, ["uav3", "uav4"], strict=True))


def test_the_characters_start_together_when_all_are_ready() -> None:
    book = _book()
    for vid in ("uav1", "uav2", "uav3"):
        _online(book, vid, 0.0)
    ids, _ = _phrase(book, "新年快", 1.0)
    first = _ready(book, "uav1", ids[0], 5.0)
    assert not first.ok and first.error is not None and first.error.code == "phrase_waits"
    assert "年" in first.message and book.jobs[ids[0]].writing_since_s is None
    assert not _ready(book, "uav2", ids[1], 5.2).ok
    assert _ready(book, "uav3", ids[2], 5.4).ok  # the last one: the phrase starts
    assert _ready(book, "uav1", ids[0], 5.5).ok and _ready(book, "uav2", ids[1], 5.7).ok
    assert [book.jobs[j].writing_since_s for j in ids] == [5.5, 5.7, 5.4]


def test_a_stale_ready_report_does_not_count() -> None:
    book = _book(lost_after_s=1.5)
    for vid in ("uav1", "uav2"):
        _online(book, vid, 0.0)
    ids, _ = _phrase(book, "你好", 1.0)
    assert not _ready(book, "uav1", ids[0], 2.0).ok
    book.status(VehicleStatus(vehicle_id="uav1", kind="q", state="writing", job_id=ids[0]), 3.0)
    book.status(VehicleStatus(vehicle_id="uav2", kind="q", state="writing", job_id=ids[1]), 3.0)
    assert not _ready(book, "uav2", ids[1], 4.0).ok  # uav1's is 2 s old: it may have given up
    assert _ready(book, "uav1", ids[0], 4.2).ok


def test_a_character_taken_back_before_the_start_takes_its_phrase_back() -> None:
    book = _book()
    for vid in ("uav1", "uav2", "uav3"):
        _online(book, vid, 0.0)
    ids, _ = _phrase(book, "新年快", 1.0)
    refused = CommandReply(ok=False, message="busy")
    eff = book.assignment_result("uav2", ids[1], refused, 1.5)
    assert {book.jobs[j].state for j in ids} == {"queued"}
    cancels = {(v, c.job_id) for v, c in eff.commands if c.command == "cancel"}
    assert cancels == {("uav1", ids[0]), ("uav3", ids[2])}
    assert all(not book.jobs[j].rewrite_alone for j in ids)
    # uav2 backs off; when it may take jobs again, all three go out together
    book.report(AgentReport(vehicle_id="uav1", job_id=ids[0], event="holding"), 1.6)
    assert book.jobs[ids[0]].state == "queued"  # not reclaimed alone
    eff = book.tick(1.5 + book.config.refuse_backoff_s)
    assert sorted(_assigned(eff)) == sorted(ids)


def test_a_character_failing_after_the_start_is_rewritten_alone_on_its_board() -> None:
    book = _book()
    for vid in ("uav1", "uav2", "uav3", "uav4"):
        _online(book, vid, 0.0)
    ids, _ = _phrase(book, "新年快", 1.0)  # b1-b3
    for now in (5.0, 5.5):  # the last one releases the phrase; the others hear it next time
        for vid, job_id in zip(["uav1", "uav2", "uav3"], ids, strict=True):
            _ready(book, vid, job_id, now)
    assert all(book.jobs[j].writing_since_s is not None for j in ids)
    book.report(AgentReport(vehicle_id="uav1", job_id=ids[0], event="started"), 5.1)
    error = ErrorInfo(code="deviation", message="gust")
    failed = AgentReport(
        vehicle_id="uav2", job_id=ids[1], event="failed", progress=0.4, error=error
    )
    _, eff = book.report(failed, 8.0)
    again = book.jobs[ids[1]]
    assert again.state == "queued" and again.rewrite_alone and again.board_id == "b2"
    assert [book.jobs[j].state for j in (ids[0], ids[2])] == ["writing", "assigned"]
    assert "b2" in book.dirty_boards and not _assigned(eff)
    _online(book, "uav4", 9.0)  # b4 is free, but the character belongs on b2
    assert book.jobs[ids[1]].state == "queued"
    _, eff = book.operator(OperatorCommand(command="fresh_sheet", board_id="b2"), 10.0)
    assert _assigned(eff) == {ids[1]: "uav2"}
    assert _ready(book, "uav2", ids[1], 25.0).ok  # alone: released at once


def test_a_phrase_longer_than_the_row_is_refused_in_one_line_with_the_limit() -> None:
    show = load_show(AIRSHOW)
    with pytest.raises(SubmissionError) as caught:
        validate_submission(SubmitRequest(text="恭喜发财快乐", phrase=True), show)
    assert str(caught.value) == "a phrase of 6 characters is longer than the row: at most 4"
    with pytest.raises(SubmissionError, match="no spaces"):
        validate_submission(SubmitRequest(text="新 年", phrase=True), show)
    accepted = validate_submission(SubmitRequest(text="新年快乐", phrase=True), show)
    assert [c.label for c in accepted.characters] == list("新年快乐")


def test_a_phrase_counts_as_its_characters_in_the_quotas() -> None:
    quotas = SubmitQuotas(QuotaPolicy(client_per_minute=6, client_max_waiting=10))
    assert quotas.refusal("submitter@a", 0, 0.0, count=4) is None
    refusal = quotas.refusal("submitter@a", 4, 1.0, count=4)
    assert refusal is not None and refusal.code == "rate_limited"  # 8 > 6 a minute
    assert quotas.refusal("submitter@b", 7, 0.0, count=4) is not None  # 11 waiting > 10
    assert quotas.refusal("submitter@c", 6, 0.0, count=4) is None


def test_a_full_queue_refuses_the_whole_phrase() -> None:
    book = _book(max_queue=3)
    reply, eff = book.submit_phrase(
        ["a", "b", "c", "d"],
        SubmitRequest(text="新年快乐", phrase=True),
        [5.0] * 4,
        now_s=0.0,
        submitted_by="kiosk",
    )
    assert not reply.ok and reply.error is not None and "4 characters" in reply.error.message
    assert not book.jobs and not eff.jobs


class PhraseMachine(RuleBasedStateMachine):
    """Phrases and single jobs, agents that get ready, write, fail, refuse or get lost, and time.

    Each decision is checked as it comes: the together-characters of a phrase are all assigned
    in one decision or none is, to adjacent boards in reading order; a character rewritten alone
    goes to its own board, alone; no ready report is acknowledged before its phrase's others
    reported ready."""

    @initialize(moderation=st.booleans())
    def start(self, moderation: bool) -> None:
        self.book = Book(
            CoreConfig(show_id="t", vehicles=VEHICLES, moderation=moderation, max_handbacks=6),
            now_s=0.0,
        )
        self.now = 0.0
        self.count = 0
        self.agent_job: dict[str, str | None] = {v.vehicle_id: None for v in VEHICLES}
        self.released: set[str] = set()
        """Phrases whose vehicles were let write."""
        self.acked: dict[str, float] = {}
        """Job -> time its ready report was acknowledged."""
        self.ready_at: dict[str, tuple[int, float]] = {}

    def _apply(self, eff: Effects) -> None:
        book = self.book
        given = _assigned(eff)
        for vid, cmd in eff.commands:
            if cmd.command == "assign" and cmd.job is not None and book.vehicles[vid].alive:
                self.agent_job[vid] = cmd.job.job_id
            elif cmd.command in ("land", "estop") or self.agent_job[vid] == cmd.job_id:
                self.agent_job[vid] = None  # stopped, or told to drop the job it flies
        phrases: dict[str, list[str]] = {}
        for job_id, vid in given.items():
            job = book.jobs[job_id]
            if job.phrase is None:
                continue
            if job.rewrite_alone:  # alone, to its own board
                assert book.vehicles[vid].info.board_id == job.board_id
                continue
            phrases.setdefault(job.phrase.phrase_id, []).append(job_id)
        for phrase_id, job_ids in phrases.items():
            members = [
                j
                for j in book.jobs.values()
                if j.phrase and j.phrase.phrase_id == phrase_id and not j.rewrite_alone
            ]
            # all or none: no character of the phrase is left waiting behind this dispatch
            assert not [j for j in members if j.state in ("queued", "awaiting_approval")], members
            seated = sorted((book.jobs[j] for j in job_ids), key=lambda j: j.phrase.index)  # type: ignore[union-attr]
            boards = [ROW.index(j.board_id or "") for j in seated]
            assert boards == list(range(boards[0], boards[0] + len(boards))), boards

    def _submit_single(self) -> None:
        job_id = f"s{self.count}"
        self.count += 1
        req = SubmitRequest(text="L")
        self._apply(self.book.submit(job_id, req, label="L", estimate_s=10, now_s=self.now)[1])

    @rule(size=st.integers(1, 4), single=st.booleans())
    def submit(self, size: int, single: bool) -> None:
        if single:
            self._submit_single()
            return
        ids = [f"p{self.count}_{i}" for i in range(size)]
        self.count += 1
        req = SubmitRequest(text="新年快乐"[:size], phrase=True)
        self._apply(self.book.submit_phrase(ids, req, [10.0] * size, now_s=self.now)[1])

    @rule(data=st.data(), command=st.sampled_from(["approve", "reject", "cancel"]))
    def job_command(
        self, data: st.DataObject, command: Literal["approve", "reject", "cancel"]
    ) -> None:
        if not self.book.jobs:
            return
        job_id = data.draw(st.sampled_from(sorted(self.book.jobs)))
        self._apply(
            self.book.operator(OperatorCommand(command=command, job_id=job_id), self.now)[1]
        )

    @rule(vid=st.sampled_from([v.vehicle_id for v in VEHICLES]))
    def online(self, vid: str) -> None:
        self._apply(self.book.liveliness(vid, True, self.now))
        job = self.agent_job[vid]
        state: VehicleStateName = "writing" if job else "idle"
        status = VehicleStatus(vehicle_id=vid, kind="q", state=state, job_id=job)
        self._apply(self.book.status(status, self.now))

    @rule(vid=st.sampled_from([v.vehicle_id for v in VEHICLES]))
    def vanish(self, vid: str) -> None:
        self._apply(self.book.liveliness(vid, False, self.now))

    @rule(
        vid=st.sampled_from([v.vehicle_id for v in VEHICLES]),
        event=st.sampled_from(["ready", "ready", "started", "done", "failed"]),
    )
    def report(self, vid: str, event: str) -> None:
        job_id = self.agent_job[vid]
        if job_id is None:
            return
        job = self.book.jobs[job_id]
        if event == "ready":
            rep = AgentReport(vehicle_id=vid, job_id=job_id, event="holding", planned_duration_s=5)
        else:
            error = ErrorInfo(code="deviation", message="gust") if event == "failed" else None
            rep = AgentReport(vehicle_id=vid, job_id=job_id, event=event, progress=0.5, error=error)  # type: ignore[arg-type]
        if event == "started" and job_id not in self.acked:
            return  # an agent writes only after its ready report was acknowledged
        reply, eff = self.book.report(rep, self.now)
        if event == "ready" and job.active:
            self.ready_at[job_id] = (job.attempts, self.now)
            if reply.ok:
                self._released(job)
                self.acked[job_id] = self.now
        if event in ("done", "failed") or (
            not reply.ok and reply.error and reply.error.code == "not_assigned"
        ):
            self.agent_job[vid] = None
            self.acked.pop(job_id, None)
        self._apply(eff)

    def _released(self, job: Job) -> None:
        """A ready report was acknowledged: every other together-character dispatched with it
        reported ready within ``lost_after_s``, or the phrase had been released already."""
        if job.phrase is None or job.rewrite_alone or job.phrase.phrase_id in self.released:
            return
        others = [
            j
            for j in self.book.jobs.values()
            if j.phrase
            and j.phrase.phrase_id == job.phrase.phrase_id
            and j.job_id != job.job_id
            and not j.rewrite_alone
            and not j.final
        ]
        for other in others:
            attempt, at = self.ready_at.get(other.job_id, (-1, -1e9))
            assert attempt == other.attempts and self.now - at < self.book.config.lost_after_s, (
                job,
                other,
            )
        self.released.add(job.phrase.phrase_id)

    @rule(vid=st.sampled_from([v.vehicle_id for v in VEHICLES]))
    def refuse(self, vid: str) -> None:
        job = self.book.active_job_of(vid)
        if job is None or job.state != "assigned":
            return
        self.agent_job[vid] = None
        refused = CommandReply(ok=False, message="busy")
        self._apply(self.book.assignment_result(vid, job.job_id, refused, self.now))

    @rule(board=st.sampled_from(ROW))
    def fresh_sheet(self, board: str) -> None:
        self._apply(
            self.book.operator(OperatorCommand(command="fresh_sheet", board_id=board), self.now)[1]
        )

    @rule(dt=st.sampled_from([0.2, 0.5, 1.0, 3.0]))
    def tick(self, dt: float) -> None:
        self.now += dt
        self._apply(self.book.tick(self.now))

    @invariant()
    def together_characters_are_all_out_or_all_waiting(self) -> None:
        if not hasattr(self, "book"):
            return
        by_phrase: dict[str, list[Job]] = {}
        for job in self.book.jobs.values():
            if job.phrase is not None and not job.rewrite_alone and not job.final:
                by_phrase.setdefault(job.phrase.phrase_id, []).append(job)
        for jobs in by_phrase.values():
            active = [j for j in jobs if j.active]
            if active:  # dispatched together: none left waiting, all in one decision
                assert len(active) == len(jobs), jobs
                begun = any(j.writing_since_s is not None for j in active)
                assert begun or len({j.assigned_at_s for j in active}) == 1, jobs

    @invariant()
    def a_character_rewritten_alone_stays_on_its_board(self) -> None:
        if not hasattr(self, "book"):
            return
        for job in self.book.jobs.values():
            if job.rewrite_alone and job.active:
                assert self.book.vehicles[job.vehicle_id or ""].info.board_id == job.board_id


TestPhraseMachine = PhraseMachine.TestCase
TestPhraseMachine.settings = settings(
    max_examples=150,
    stateful_step_count=40,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
)
